# The viewer's tests (ctest view_script, view_bad_input), run with cmake -P:
#   MODE=script: limn-view runs tests/data/view_script.json under Xvfb (a dynamic-depth surface,
#     fixed depth, the cage, a paint stroke, undo/redo, .lot save and load, a material stroke
#     (metallic, rough, height: PBR-shaded), a simplify run and
#     its export); its screenshots must not be blank and the stroke's colour must appear where
#     it should (painted, redone with nearest texels, reloaded) and nowhere else (before,
#     undone). Then --frames/--screenshot.
#   MODE=bad: a missing mesh, a bad mesh and bad scripts exit 2 with one line naming the file,
#     before any window opens.
# Variables: VIEW, CHECK (limn-view-check), XVFB_RUN, SCRIPT, BAD_MESH, WORK_DIR.
file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR})

function(check image)
  execute_process(COMMAND ${CHECK} ${WORK_DIR}/${image} ${ARGN} RESULT_VARIABLE rc
                  OUTPUT_VARIABLE out ERROR_VARIABLE out)
  message(STATUS "${out}")
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${image}: check failed (${ARGN})")
  endif()
endfunction()

function(expect_input_error what)
  execute_process(COMMAND ${VIEW} ${ARGN} WORKING_DIRECTORY ${WORK_DIR} RESULT_VARIABLE rc
                  OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 60)
  string(STRIP "${err}" err)
  message(STATUS "${what}: exit ${rc}: ${err}")
  if(NOT rc EQUAL 2)
    message(FATAL_ERROR "${what}: expected exit code 2, got ${rc}")
  endif()
  if(NOT err MATCHES "^limn-view: error: [^\n]*${what}[^\n]*$")
    message(FATAL_ERROR "${what}: expected one line naming it on stderr, got '${err}'")
  endif()
endfunction()

if(MODE STREQUAL "script")
  set(xvfb ${XVFB_RUN} -a -s "-screen 0 1280x1024x24")
  execute_process(COMMAND ${xvfb} ${VIEW} --size 640x480 --samples 0 --script ${SCRIPT}
                  WORKING_DIRECTORY ${WORK_DIR} RESULT_VARIABLE rc TIMEOUT 240
                  ERROR_VARIABLE log)
  message(STATUS "${log}")
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "limn-view --script ${SCRIPT}: exit ${rc}")
  endif()
  # The live stroke (one point a frame) reports where its time went and the library's cost for
  # the same points, which must be the same dabs.
  if(NOT log MATCHES "stroke [0-9]+ \\(live, 4 points, one a frame\\): ([0-9]+) dabs in [0-9.]+ ms: painting [0-9.]+ ms, texture uploads [0-9.]+ ms \\([0-9]+, [0-9]+ words\\), frames [0-9.]+ ms; the library alone: ([0-9]+) dabs in [0-9.]+ ms; viewer/library [0-9.]+x")
    message(FATAL_ERROR "no report line for the live stroke")
  endif()
  if(CMAKE_MATCH_1 LESS 4 OR NOT CMAKE_MATCH_1 EQUAL CMAKE_MATCH_2)
    message(FATAL_ERROR "live stroke: ${CMAKE_MATCH_1} dabs in the viewer, ${CMAKE_MATCH_2} alone")
  endif()
  # Framing, from the lines the screenshots log: the cage lies wholly in the view area (right of
  # the panel while it shows) and spans most of it, with the panel shown and hidden.
  foreach(shot framed framed-full)
    if(NOT log MATCHES "wrote ${shot}.png \\(([0-9]+)x([0-9]+)\\), view x ([0-9]+)-([0-9]+), cage x (-?[0-9]+)-(-?[0-9]+) y (-?[0-9]+)-(-?[0-9]+)")
      message(FATAL_ERROR "no framing line for ${shot}.png")
    endif()
    set(h ${CMAKE_MATCH_2})
    set(x0 ${CMAKE_MATCH_3})
    set(x1 ${CMAKE_MATCH_4})
    set(cx0 ${CMAKE_MATCH_5})
    set(cx1 ${CMAKE_MATCH_6})
    set(cy0 ${CMAKE_MATCH_7})
    set(cy1 ${CMAKE_MATCH_8})
    math(EXPR w "${x1} - ${x0}")
    math(EXPR cw "${cx1} - ${cx0}")
    math(EXPR ch "${cy1} - ${cy0}")
    if(cx0 LESS x0 OR cx1 GREATER x1 OR cy0 LESS 0 OR cy1 GREATER h)
      message(FATAL_ERROR "${shot}: the cage (x ${cx0}-${cx1}, y ${cy0}-${cy1}) leaves the view (x ${x0}-${x1}, height ${h})")
    endif()
    math(EXPR wide "10 * ${cw} - 6 * ${w}")
    math(EXPR tall "10 * ${ch} - 6 * ${h}")
    if(wide LESS 0 AND tall LESS 0)
      message(FATAL_ERROR "${shot}: the cage (${cw}x${ch} px) fills under 60% of the view (${w}x${h})")
    endif()
    set(${shot}_x0 ${x0})
  endforeach()
  if(NOT framed_x0 GREATER 100 OR NOT framed-full_x0 EQUAL 0)
    message(FATAL_ERROR "the view starts at x ${framed_x0} with the panel (expected right of it) and ${framed-full_x0} without")
  endif()
  check(surface.png)
  check(fixed.png)
  check(cage.png)
  check(before.png --absent 1,0,1)
  check(painted.png --present 1,0,1 --min-pixels 500)
  check(undone.png --absent 1,0,1)
  check(nearest.png --present 1,0,1 --min-pixels 500)
  check(reloaded.png --present 1,0,1 --min-pixels 500)
  # A stroke carrying a material (metal, glossy, raised), drawn with the material shading.
  check(material.png --present 0,1,0 --min-pixels 300)
  check(clusters.png)
  foreach(f view.lot simplified.obj)
    if(NOT EXISTS ${WORK_DIR}/${f})
      message(FATAL_ERROR "the script did not write ${f}")
    endif()
  endforeach()
  execute_process(COMMAND ${xvfb} ${VIEW} --shape cube --size 320x240 --samples 0 --frames 2
                          --screenshot frames.png
                  WORKING_DIRECTORY ${WORK_DIR} RESULT_VARIABLE rc TIMEOUT 120)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "limn-view --frames 2 --screenshot: exit ${rc}")
  endif()
  check(frames.png)
elseif(MODE STREQUAL "bad")
  expect_input_error(no-such-mesh.obj no-such-mesh.obj)
  expect_input_error(${BAD_MESH} ${BAD_MESH})
  file(WRITE ${WORK_DIR}/broken.json "[{\"orbit\": [1, 2]}, ")
  expect_input_error(broken.json --script broken.json)
  file(WRITE ${WORK_DIR}/unknown.json "[{\"orbit\": [1, 2]}, {\"fly\": true}]")
  expect_input_error("unknown.json: action 2" --script unknown.json)
  file(WRITE ${WORK_DIR}/stroke.json "[{\"stroke\": {\"points\": [[1, 2]], \"radius\": -3}}]")
  expect_input_error("stroke.json: action 1" --script stroke.json)
  expect_input_error(no-such-script.json --script no-such-script.json)
else()
  message(FATAL_ERROR "MODE must be script or bad")
endif()
