# ctest: hapticfield_view --screenshot (off-screen, no display) with the
# mouse probe held at a known pixel and with the simulated arm's scripted
# hand; view_check finds the picture in each screenshot and the cursor at
# the probe's position.
# cmake -DVIEW=... -DCHECK=... -DPICTURE=... -DWORK_DIR=... -P run_screenshot.cmake
file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR})

function(check_shot shot probe)
  execute_process(COMMAND ${CHECK} ${shot} ${PICTURE} ${probe} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  message(STATUS "${out}${err}")
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "view_check failed for ${shot} at ${probe}")
  endif()
endfunction()

# the mouse probe, held at 150,120 px
execute_process(COMMAND ${VIEW} ${PICTURE} --start 150,120 --seconds 0.3 --realtime off
                        --screenshot ${WORK_DIR}/mouse.png
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 60)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "hapticfield_view (mouse) failed (${rc}): ${out}${err}")
endif()
check_shot(${WORK_DIR}/mouse.png 150,120)

# the cursor must move with the probe: the same check at another pixel fails
execute_process(COMMAND ${CHECK} ${WORK_DIR}/mouse.png ${PICTURE} 400,300 RESULT_VARIABLE rc OUTPUT_QUIET)
if(rc EQUAL 0)
  message(FATAL_ERROR "view_check found the cursor where the probe was not")
endif()

# the simulated arm: the tool says where its scripted hand left the probe
execute_process(COMMAND ${VIEW} ${PICTURE} --device sim --seconds 1.5 --realtime off --field texture
                        --screenshot ${WORK_DIR}/sim_texture.png
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 60)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "hapticfield_view (sim) failed (${rc}): ${out}${err}")
endif()
string(REGEX MATCH "probe at ([-0-9.]+),([-0-9.]+) px" found "${out}")
if(NOT found)
  message(FATAL_ERROR "hapticfield_view (sim) did not say where the probe was: ${out}")
endif()
message(STATUS "${out}")
# the texture field's underlay is not the picture: view_check must not find it
execute_process(COMMAND ${CHECK} ${WORK_DIR}/sim_texture.png ${PICTURE} ${CMAKE_MATCH_1},${CMAKE_MATCH_2}
                RESULT_VARIABLE rc OUTPUT_VARIABLE out)
if(rc EQUAL 0)
  message(FATAL_ERROR "the texture view shows the picture itself: ${out}")
endif()

execute_process(COMMAND ${VIEW} ${PICTURE} --device sim --seconds 1.5 --realtime off --screenshot ${WORK_DIR}/sim.png
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 60)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "hapticfield_view (sim) failed (${rc}): ${out}${err}")
endif()
string(REGEX MATCH "probe at ([-0-9.]+),([-0-9.]+) px" found "${out}")
if(NOT found)
  message(FATAL_ERROR "hapticfield_view (sim) did not say where the probe was: ${out}")
endif()
check_shot(${WORK_DIR}/sim.png ${CMAKE_MATCH_1},${CMAKE_MATCH_2})

# no display and no --screenshot: one clear line, exit 1, no crash
execute_process(COMMAND ${CMAKE_COMMAND} -E env --unset=DISPLAY --unset=WAYLAND_DISPLAY ${VIEW} ${PICTURE}
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 60)
if(NOT rc EQUAL 1 OR NOT err MATCHES "^hapticfield_view: no display")
  message(FATAL_ERROR "without a display: exit ${rc}, '${err}'")
endif()
