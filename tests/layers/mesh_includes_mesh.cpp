// Control probe: a mesh-layer file including a mesh-layer header builds.
#include "gridshell/mesh/mesh.h"

int main() { return gridshell::TriangleMesh().vertex_count(); }
