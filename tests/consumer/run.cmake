# ctest driver: install the built limn into a scratch prefix, then configure, build and run the
# consumer project against it with find_package(limn).
file(REMOVE_RECURSE ${WORK_DIR})
execute_process(COMMAND ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${WORK_DIR}/prefix
                RESULT_VARIABLE rc)
if(rc)
  message(FATAL_ERROR "install failed: ${rc}")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} -S ${SOURCE_DIR} -B ${WORK_DIR}/build -G ${GENERATOR}
                        -DCMAKE_PREFIX_PATH=${WORK_DIR}/prefix "-DCMAKE_CXX_FLAGS=${CONSUMER_FLAGS}"
                RESULT_VARIABLE rc)
if(rc)
  message(FATAL_ERROR "configuring the consumer failed: ${rc}")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} --build ${WORK_DIR}/build RESULT_VARIABLE rc)
if(rc)
  message(FATAL_ERROR "building the consumer failed: ${rc}")
endif()
foreach(exe consumer consumer_subdiv)
  execute_process(COMMAND ${WORK_DIR}/build/${exe} RESULT_VARIABLE rc)
  if(rc)
    message(FATAL_ERROR "${exe} failed: ${rc}")
  endif()
endforeach()
# The layers link only what they use: the subdivision-only program loads no Embree, tinygltf,
# tinyobjloader or OpenGL library, where the whole library's loads tinygltf and libepoxy (so the
# check can fail). Embree is opened only when a program first casts a ray (core/embree.hpp).
execute_process(COMMAND ldd ${WORK_DIR}/build/consumer_subdiv OUTPUT_VARIABLE subdiv_libs)
execute_process(COMMAND ldd ${WORK_DIR}/build/consumer OUTPUT_VARIABLE all_libs)
# (Sanitizer builds link Embree into the core: src/core/embree.cpp says why.)
set(heavy "tinygltf|tinyobjloader|libGL|libEGL|libOpenGL|epoxy")
if(NOT EMBREE_LINKED)
  set(heavy "embree|${heavy}")
endif()
if(subdiv_libs MATCHES "(${heavy})")
  message(FATAL_ERROR "consumer_subdiv (limn::subdiv only) loads ${CMAKE_MATCH_1}:\n${subdiv_libs}")
endif()
if(NOT all_libs MATCHES "tinygltf" OR NOT all_libs MATCHES "epoxy")
  message(FATAL_ERROR "consumer (limn::limn) should load tinygltf and libepoxy:\n${all_libs}")
endif()
if(all_libs MATCHES "embree" AND NOT EMBREE_LINKED)
  message(FATAL_ERROR "consumer (limn::limn) loads Embree at start:\n${all_libs}")
endif()
foreach(f bin/limn include/limn/mesh/mesh.hpp include/limn/io/mesh_io.hpp include/limn/version.hpp)
  if(NOT EXISTS ${WORK_DIR}/prefix/${f})
    message(FATAL_ERROR "not installed: ${f}")
  endif()
endforeach()
# The installed CLI starts without the GL stack and finds its GL module (render, demo) where it
# was installed.
execute_process(COMMAND ldd ${WORK_DIR}/prefix/bin/limn OUTPUT_VARIABLE cli_libs)
if(cli_libs MATCHES "epoxy|libEGL|libGL")
  message(FATAL_ERROR "the limn CLI loads OpenGL at start:\n${cli_libs}")
endif()
execute_process(COMMAND ${WORK_DIR}/prefix/bin/limn shape cube -o ${WORK_DIR}/cube.obj
                RESULT_VARIABLE rc)
execute_process(COMMAND ${WORK_DIR}/prefix/bin/limn render ${WORK_DIR}/cube.obj
                        -o ${WORK_DIR}/cube.png --samples 1 --resolution 64x48
                RESULT_VARIABLE rc2 ERROR_VARIABLE err)
if(rc OR rc2 OR NOT EXISTS ${WORK_DIR}/cube.png)
  message(FATAL_ERROR "the installed limn render failed (${rc}, ${rc2}): ${err}")
endif()
