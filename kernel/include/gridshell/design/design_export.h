// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — human-readable views of a design: the flat grid as SVG (to scale), the spatial grid
// as OBJ, and the distance maps with the cladding curves as SVG.
#pragma once

#include <string>

#include "gridshell/design/design.h"

namespace gridshell {

/// The planar grid to scale (1 SVG user unit = 1 mesh unit, lamellas drawn at their width),
/// crossings as dots, notches as slots along the member (length |s - s̄| in the sliding
/// direction), anchors as squares, members labelled g1.., h1...
std::string planar_svg(const Design& design, double lamella_width);

/// The patch as faces and every member's geodesic as a polyline (`l`), one object per member.
std::string spatial_obj(const Design& design);

/// D - D̄(ᾱ) of both families as colour maps (blue < 0 < red) with the cladding curves and the
/// chosen members marked.
std::string maps_svg(const Design& design);

}  // namespace gridshell
