# ctest driver: install the built limn into a scratch prefix and import the Python package from
# its dist-packages folder alone (not the build tree).
file(REMOVE_RECURSE ${WORK_DIR})
execute_process(COMMAND ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${WORK_DIR}/prefix
                OUTPUT_QUIET RESULT_VARIABLE rc)
if(rc)
  message(FATAL_ERROR "install failed: ${rc}")
endif()
set(site ${WORK_DIR}/prefix/${PY_DIR})
execute_process(
  COMMAND ${CMAKE_COMMAND} -E env PYTHONPATH=${site} ${PYTHON} -c
          "import limn, pathlib; assert pathlib.Path(limn.__file__).parent == pathlib.Path('${site}/limn'), limn.__file__; m = limn.shape('cube'); assert limn.info(m)['closed']; print(limn.__version__, m)"
  WORKING_DIRECTORY ${WORK_DIR} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(rc)
  message(FATAL_ERROR "import limn from ${site} failed: ${out}${err}")
endif()
message(STATUS "${out}")
