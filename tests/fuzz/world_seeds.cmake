# SPDX-License-Identifier: MIT
# The seed corpus of the world loader's fuzz target (tests/fuzz/fuzz_world.cpp): the sample world, the tiny
# world (samples/tiny_world.py) and the shared levels when they are there. cmake -DOUT=DIR -DROOT=REPO
# [-DPYTHON=python3] -P world_seeds.cmake
# ${OUT}-new: an empty folder for what a run adds, so that the seeds stay the corpus of every run.
file(REMOVE_RECURSE ${OUT} ${OUT}-new)
file(MAKE_DIRECTORY ${OUT} ${OUT}-new)
file(COPY ${ROOT}/samples/rooms.glb DESTINATION ${OUT})
file(GLOB shared ${ROOT}/../shared/worlds/*.glb)
foreach(level ${shared})
  file(COPY ${level} DESTINATION ${OUT})
endforeach()
if(PYTHON)
  execute_process(COMMAND ${PYTHON} ${ROOT}/samples/tiny_world.py ${OUT}/tiny.glb RESULT_VARIABLE failed)
  if(failed)
    message(FATAL_ERROR "samples/tiny_world.py failed")
  endif()
endif()
