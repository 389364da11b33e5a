# SPDX-License-Identifier: MIT
# Checks that every #include "folder/..." of the project goes down the layers of CONTRIBUTING.md ("Layers"):
# a folder includes only itself and the folders below it. Run: cmake -DROOT=<source dir> -P check_layers.cmake
# (ctest runs it as the test `layers`). Prints every include that climbs and fails if there is one.
cmake_minimum_required(VERSION 3.25)
if(NOT ROOT)
  message(FATAL_ERROR "check_layers.cmake: pass -DROOT=<the project's source folder>")
endif()

# folder -> the project folders its files may include (besides itself). Keep in step with CONTRIBUTING.md.
set(allowed_runtime "")
set(allowed_core "")
set(allowed_io "core;runtime")
set(allowed_voxels "core")
set(allowed_cells "core;voxels")
set(allowed_rays "core;voxels;cells")
set(allowed_occluders "core;runtime;voxels;cells;rays")
set(allowed_pvs "core;runtime;voxels;cells;rays;occluders")
set(allowed_driver "core;io;runtime;voxels;cells;rays;occluders;pvs")
set(allowed_samples "core;io")
set(allowed_viewer "core;io;runtime;voxels;cells;rays;occluders;pvs;driver")
set(project_folders runtime core io voxels cells rays occluders pvs driver samples viewer tests bench)

set(violations 0)
set(checked 0)
foreach(folder runtime core io voxels cells rays occluders pvs driver samples viewer)
  file(GLOB_RECURSE sources RELATIVE ${ROOT} ${ROOT}/${folder}/*.h ${ROOT}/${folder}/*.hpp ${ROOT}/${folder}/*.c
    ${ROOT}/${folder}/*.cpp)
  foreach(source ${sources})
    if(source MATCHES "^viewer/tests/")
      continue()  # tests may include anything
    endif()
    # The runtime loader is a library of its own: it includes nothing of the baker's (the shipped runtime
    # itself, runtime/, whose horizon it compiles in).
    set(allowed ${allowed_${folder}})
    if(source MATCHES "^io/loader/")
      set(allowed "runtime")
    endif()
    file(STRINGS ${ROOT}/${source} includes REGEX "^[ \t]*#[ \t]*include[ \t]+\"[^\"]+\"")
    foreach(line ${includes})
      string(REGEX REPLACE "^[ \t]*#[ \t]*include[ \t]+\"([^\"]+)\".*$" "\\1" path "${line}")
      math(EXPR checked "${checked} + 1")
      if(NOT path MATCHES "/")
        continue()  # a file of the same folder
      endif()
      string(REGEX REPLACE "/.*$" "" target "${path}")
      if(NOT target IN_LIST project_folders)
        continue()  # a library's header (pvsbake/loader.h, ...)
      endif()
      if((source MATCHES "^io/loader/" AND NOT target IN_LIST allowed) OR
         (NOT target STREQUAL folder AND NOT target IN_LIST allowed))
        message("${source}: includes \"${path}\": ${folder}/ may include only ${folder}/ and: ${allowed}")
        math(EXPR violations "${violations} + 1")
      endif()
    endforeach()
  endforeach()
endforeach()

if(violations GREATER 0)
  message(FATAL_ERROR "check_layers: ${violations} include(s) climb the layers (CONTRIBUTING.md, \"Layers\")")
endif()
message(STATUS "check_layers: ${checked} includes, all down the layers")
