# SPDX-License-Identifier: GPL-3.0-or-later
# gridshell_layer(NAME SOURCES dir HEADERS dir [DEPENDS lower...] [PRIVATE_LIBS libs...]): one
# layer as one static library gridshell_NAME, built from SOURCES/*.cpp, whose public headers are
# the folder HEADERS, included as "gridshell/NAME/x.h".
#
# No target sees the headers' parent folder whole: each layer gets an include root of its own in
# the build tree holding only a link gridshell/NAME -> HEADERS, and passes it on to the layers
# above through target_link_libraries. So a lower layer that includes a higher layer's header
# does not compile ("gridshell/design/patch.h: No such file or directory"), and it cannot link
# one either: a layer target names only the layers below it. tests/layers checks both
# (docs/architecture.md).
set(GRIDSHELL_LAYER_INCLUDE_ROOT ${CMAKE_BINARY_DIR}/layer-include)

function(gridshell_layer name)
  cmake_parse_arguments(LAYER "" "SOURCES;HEADERS" "DEPENDS;PRIVATE_LIBS" ${ARGN})
  file(GLOB sources CONFIGURE_DEPENDS ${LAYER_SOURCES}/*.cpp)
  add_library(gridshell_${name} STATIC ${sources})
  set(root ${GRIDSHELL_LAYER_INCLUDE_ROOT}/${name})
  file(MAKE_DIRECTORY ${root}/gridshell)
  if(NOT EXISTS ${root}/gridshell/${name})
    file(CREATE_LINK ${LAYER_HEADERS} ${root}/gridshell/${name} SYMBOLIC)
  endif()
  target_include_directories(gridshell_${name} PUBLIC ${root} PRIVATE ${LAYER_SOURCES})
  target_link_libraries(gridshell_${name} PUBLIC ${LAYER_DEPENDS} PRIVATE ${LAYER_PRIVATE_LIBS})
endfunction()
