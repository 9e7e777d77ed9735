# ctest: the 3D view of a shape, drawn off-screen. A generated UV sphere
# (shape_check --make-sphere) is scaled by the tools to 80 mm across (radius
# 40 mm) and seen head-on (--view 0,0) from 200 mm: shape_check finds its
# disc at the pinhole projection's radius and the proxy and HIP markers on
# it. hapticfield_view --shape with the mouse probe (--screenshot), and
# servo_demo --shape on the simulated arm on the virtual clock (--snapshot,
# after 3.4 s the scripted hand presses the sphere near its top); and the
# viewer's --radius 5: shape_check --ball finds the tool's ball at its
# projected size.
# cmake -DVIEW=... (may be empty) -DDEMO=... -DCHECK=... -DWORK_DIR=... -P run_shape_shots.cmake
file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR})
set(sphere ${WORK_DIR}/sphere.obj)
execute_process(COMMAND ${CHECK} --make-sphere ${sphere} RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "shape_check could not write the sphere")
endif()

function(check_sphere shot)
  execute_process(COMMAND ${CHECK} ${shot} 40 200 RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  message(STATUS "${out}${err}")
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "shape_check failed for ${shot}")
  endif()
  # the check can fail: a sphere of 30 mm is not what is drawn
  execute_process(COMMAND ${CHECK} ${shot} 30 200 RESULT_VARIABLE rc OUTPUT_QUIET)
  if(rc EQUAL 0)
    message(FATAL_ERROR "shape_check took the 40 mm sphere in ${shot} for a 30 mm one")
  endif()
endfunction()

if(VIEW)
  execute_process(COMMAND ${VIEW} --shape ${sphere} --view 0,0 --distance 200 --seconds 0.3 --realtime off
                          --screenshot ${WORK_DIR}/view.png
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 60)
  message(STATUS "${out}")
  if(NOT rc EQUAL 0 OR NOT out MATCHES "screenshot: ")
    message(FATAL_ERROR "hapticfield_view --shape failed (${rc}): ${out}${err}")
  endif()
  check_sphere(${WORK_DIR}/view.png)
  # the tool's ball, r 5 mm: the HIP and the proxy start 5 mm + r above the top
  # (z = -1 + 10 = 9 mm), the eye 200 mm above the centre (z = -41 + 200 = 159 mm):
  # the ball is seen on the axis 150 mm away
  execute_process(COMMAND ${VIEW} --shape ${sphere} --radius 5 --view 0,0 --distance 200 --seconds 0.3 --realtime off
                          --screenshot ${WORK_DIR}/ball.png
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 60)
  message(STATUS "${out}")
  if(NOT rc EQUAL 0 OR NOT out MATCHES "ball \\(r 5 mm\\) centred 150.000 mm from the eye")
    message(FATAL_ERROR "hapticfield_view --shape --radius 5 failed (${rc}): ${out}${err}")
  endif()
  execute_process(COMMAND ${CHECK} --ball ${WORK_DIR}/ball.png 5 150 RESULT_VARIABLE rc OUTPUT_VARIABLE out
                  ERROR_VARIABLE err)
  message(STATUS "${out}${err}")
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "shape_check --ball failed for ${WORK_DIR}/ball.png")
  endif()
  # and can fail: a ball of 4 mm is not what is drawn
  execute_process(COMMAND ${CHECK} --ball ${WORK_DIR}/ball.png 4 150 RESULT_VARIABLE rc OUTPUT_QUIET)
  if(rc EQUAL 0)
    message(FATAL_ERROR "shape_check took the 5 mm ball for a 4 mm one")
  endif()
  # a height map (the example picture) draws and exits cleanly
  execute_process(COMMAND ${VIEW} --shape ${CMAKE_CURRENT_LIST_DIR}/../../examples/data/coffee.png --height-mm 2
                          --seconds 0.1 --realtime off --screenshot ${WORK_DIR}/height.png
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 60)
  if(NOT rc EQUAL 0 OR NOT EXISTS ${WORK_DIR}/height.png)
    message(FATAL_ERROR "hapticfield_view --shape (a height map) failed (${rc}): ${out}${err}")
  endif()
endif()

execute_process(COMMAND ${DEMO} --shape ${sphere} --clock virtual --seconds 3.4 --view 0,0 --distance 200
                        --snapshot ${WORK_DIR}/demo.png
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 60)
message(STATUS "${out}")
if(NOT rc EQUAL 0 OR NOT out MATCHES "snapshot: [^\n]*, touching;")
  message(FATAL_ERROR "servo_demo --shape --snapshot failed or the hand was not on the sphere (${rc}): ${out}${err}")
endif()
if(NOT EXISTS ${WORK_DIR}/demo.png)
  message(FATAL_ERROR "servo_demo wrote no snapshot")
endif()
check_sphere(${WORK_DIR}/demo.png)
