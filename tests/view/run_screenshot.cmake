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

# hapticfield_view on the simulated arm for 1.5 s, its screenshot in
# ${WORK_DIR}/${name}.png; `probe_var` gets where the tool says the scripted
# hand left the probe ("x,y" [px]).
function(screenshot_sim name probe_var)
  execute_process(COMMAND ${VIEW} ${PICTURE} --device sim --seconds 1.5 --realtime off ${ARGN}
                          --screenshot ${WORK_DIR}/${name}.png
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 60)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "hapticfield_view (sim) failed (${rc}): ${out}${err}")
  endif()
  string(REGEX MATCH "probe at ([-0-9.]+),([-0-9.]+) px" found "${out}")
  if(NOT found)
    message(FATAL_ERROR "hapticfield_view (sim) did not say where the probe was: ${out}")
  endif()
  message(STATUS "${out}")
  set(${probe_var} "${CMAKE_MATCH_1},${CMAKE_MATCH_2}" PARENT_SCOPE)
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
screenshot_sim(sim_texture probe --field texture)
# the texture field's underlay is not the picture: view_check must not find it
execute_process(COMMAND ${CHECK} ${WORK_DIR}/sim_texture.png ${PICTURE} ${probe}
                RESULT_VARIABLE rc OUTPUT_VARIABLE out)
if(rc EQUAL 0)
  message(FATAL_ERROR "the texture view shows the picture itself: ${out}")
endif()

screenshot_sim(sim probe)
check_shot(${WORK_DIR}/sim.png ${probe})

# no display and no --screenshot: one clear line, exit 1, no crash
execute_process(COMMAND ${CMAKE_COMMAND} -E env --unset=DISPLAY --unset=WAYLAND_DISPLAY ${VIEW} ${PICTURE}
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 60)
if(NOT rc EQUAL 1 OR NOT err MATCHES "^hapticfield_view: no display")
  message(FATAL_ERROR "without a display: exit ${rc}, '${err}'")
endif()

# --field video on a clip whose frames differ visibly (a square moving 12 px
# per frame at 10 fps): the screenshot shows the frame of the loop's video
# time, which went from --from at --speed for --seconds; view_check decodes
# the clip itself.
execute_process(COMMAND ${CHECK} --make-clip ${WORK_DIR}/clip.avi RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "view_check could not write the test clip")
endif()
execute_process(COMMAND ${VIEW} ${WORK_DIR}/clip.avi --from 1 --speed 2 --seconds 0.3 --start 200,250
                        --realtime off --screenshot ${WORK_DIR}/video.png
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 60)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "hapticfield_view (video) failed (${rc}): ${out}${err}")
endif()
message(STATUS "${out}")
string(REGEX MATCH "video: ([0-9.]+) s of 3.00 s, frame ([0-9]+) shown" found "${out}")
if(NOT found)
  message(FATAL_ERROR "hapticfield_view (video) did not say its video time: ${out}")
endif()
set(video_time ${CMAKE_MATCH_1})
# 1 s + 2 x 0.3 s of loop time; a late loop only adds (without real-time
# priority on a busy machine, 520 ticks ran at 549 Hz), up to the clip's end
execute_process(COMMAND ${CHECK} ${WORK_DIR}/video.png ${WORK_DIR}/clip.avi 200,250 ${video_time} 1.59,3.0
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
message(STATUS "${out}${err}")
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "the video screenshot does not show the frame of its video time")
endif()
# the check can fail: the same screenshot is not the frame at --from
execute_process(COMMAND ${CHECK} ${WORK_DIR}/video.png ${WORK_DIR}/clip.avi 200,250 1.0 0,3 RESULT_VARIABLE rc
                OUTPUT_QUIET)
if(rc EQUAL 0)
  message(FATAL_ERROR "view_check took the frame at 1 s for the frame at ${video_time} s")
endif()

# a still field of a video: the frame at --from, held
execute_process(COMMAND ${VIEW} ${WORK_DIR}/clip.avi --field tangible --from 2.5 --seconds 0.2 --start 200,250
                        --realtime off --screenshot ${WORK_DIR}/video_still.png
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 60)
if(NOT rc EQUAL 0 OR NOT out MATCHES "video: 2.500000 s of 3.00 s, frame 25 shown")
  message(FATAL_ERROR "hapticfield_view (a still of a video) failed (${rc}): ${out}${err}")
endif()
execute_process(COMMAND ${CHECK} ${WORK_DIR}/video_still.png ${WORK_DIR}/clip.avi 200,250 2.5 2.5,2.5
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
message(STATUS "${out}${err}")
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "the still of the video is not the frame at --from")
endif()
