# The installed tools stand alone: installs into a temporary prefix, moves the prefix elsewhere, then
# asks every tool in bin/ for --help, runs servo_demo on its default picture (a short virtual-clock
# run) and servo_demo and tangible_image with --plots/--maps, checking that the picture and the plot
# script are the prefix's
# (share/hapticfield/), and that without share/hapticfield/ they are missing rather than read from the
# source tree.
#   -DBUILD_DIR= -DWORK_DIR= -DPYTHON=(an interpreter, for the matplotlib run when it has matplotlib)
file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}")

# run(EXPECT rc OUT var COMMAND ...): runs in WORK_DIR, fails unless the exit status is rc.
function(run)
  cmake_parse_arguments(R "" "EXPECT;OUT" "COMMAND" ${ARGN})
  if(NOT DEFINED R_EXPECT)
    set(R_EXPECT 0)
  endif()
  execute_process(COMMAND ${R_COMMAND} WORKING_DIRECTORY "${WORK_DIR}" RESULT_VARIABLE rc OUTPUT_VARIABLE out
                  ERROR_VARIABLE err TIMEOUT 60)
  if(NOT rc STREQUAL R_EXPECT)
    message(FATAL_ERROR "exit ${rc}, not ${R_EXPECT}: ${R_COMMAND}\n${out}\n${err}")
  endif()
  if(R_OUT)
    set(${R_OUT} "${out}${err}" PARENT_SCOPE)
  endif()
endfunction()

run(COMMAND ${CMAKE_COMMAND} --install "${BUILD_DIR}" --prefix "${WORK_DIR}/prefix" --component tools)
file(RENAME "${WORK_DIR}/prefix" "${WORK_DIR}/moved")  # nothing may point back at the first place
set(bin "${WORK_DIR}/moved/bin")
set(share "${WORK_DIR}/moved/share/hapticfield")
foreach(file data/coffee.png data/README.md hapticfield_plots.py)
  if(NOT EXISTS "${share}/${file}")
    message(FATAL_ERROR "share/hapticfield/${file} was not installed")
  endif()
endforeach()

# Every installed tool answers --help from the moved prefix (usage on stdout, exit 0); the MuJoCo
# scenes feel_mujoco names come with it.
file(GLOB installed "${bin}/*")
if(NOT installed)
  message(FATAL_ERROR "no tool was installed in bin/")
endif()
foreach(tool IN LISTS installed)
  get_filename_component(name "${tool}" NAME)
  run(COMMAND "${tool}" --help OUT out)
  if(NOT out MATCHES "^usage: ${name}")
    message(FATAL_ERROR "the installed ${name} --help did not print its usage:\n${out}")
  endif()
endforeach()
if(EXISTS "${bin}/feel_mujoco")
  foreach(file data/mujoco_table.xml data/mujoco_door.xml data/mujoco_ball.xml)
    if(NOT EXISTS "${share}/${file}")
      message(FATAL_ERROR "share/hapticfield/${file} was not installed with feel_mujoco")
    endif()
  endforeach()
endif()

# The default picture, from the prefix: a short run on the virtual clock.
run(COMMAND "${bin}/servo_demo" --clock virtual --seconds 0.2 OUT out)
if(NOT out MATCHES "200 ticks")
  message(FATAL_ERROR "servo_demo on its default picture did not run 200 ticks:\n${out}")
endif()

# The plot script, from the prefix: an interpreter that records what it was asked to run.
set(recorder "${WORK_DIR}/python_recorder.sh")
file(WRITE "${recorder}" "#!/bin/sh\nprintf '%s\\n' \"$1\" >> '${WORK_DIR}/scripts_run.txt'\nexit 3\n")
file(CHMOD "${recorder}" PERMISSIONS OWNER_READ OWNER_WRITE OWNER_EXECUTE)
set(env ${CMAKE_COMMAND} -E env --unset=HAPTICFIELD_PLOT_SCRIPT "HAPTICFIELD_PYTHON=${recorder}"
        "PATH=${WORK_DIR}/no_python")  # the recorder exits 3 ("no matplotlib here"): the tools go on
run(COMMAND ${env} "${bin}/servo_demo" --clock virtual --seconds 0.2 --plots "${WORK_DIR}/servo_plots")
run(COMMAND ${env} "${bin}/tangible_image" "${share}/data/coffee.png" --maps "${WORK_DIR}/maps")
file(STRINGS "${WORK_DIR}/scripts_run.txt" scripts_run)
list(REMOVE_DUPLICATES scripts_run)
if(NOT scripts_run STREQUAL "${share}/hapticfield_plots.py")
  message(FATAL_ERROR "the tools ran the plot script(s) '${scripts_run}', not ${share}/hapticfield_plots.py")
endif()
foreach(png servo_plots/force.png servo_plots/periods.png maps/maps.png)
  if(NOT EXISTS "${WORK_DIR}/${png}")
    message(FATAL_ERROR "${png} was not written")
  endif()
endforeach()

# With matplotlib at hand, the installed script draws the plots.
execute_process(COMMAND "${PYTHON}" -c "import matplotlib" RESULT_VARIABLE no_matplotlib OUTPUT_QUIET ERROR_QUIET)
if(no_matplotlib EQUAL 0)
  run(COMMAND ${CMAKE_COMMAND} -E env --unset=HAPTICFIELD_PLOT_SCRIPT "HAPTICFIELD_PYTHON=${PYTHON}"
              "${bin}/tangible_image" "${share}/data/coffee.png" --maps "${WORK_DIR}/maps_matplotlib" OUT out)
  if(NOT out MATCHES "drawn with matplotlib")
    message(FATAL_ERROR "the installed plot script did not draw maps.png:\n${out}")
  endif()
else()
  message(STATUS "${PYTHON} has no matplotlib: the matplotlib run is skipped")
endif()

# Without share/hapticfield/ the tools say so: nothing is read from the source tree.
file(RENAME "${share}" "${WORK_DIR}/share_away")
run(EXPECT 1 COMMAND "${bin}/servo_demo" --clock virtual --seconds 0.2 OUT out)
if(NOT out MATCHES "example picture coffee.png is not installed")
  message(FATAL_ERROR "servo_demo without share/hapticfield/ did not say its picture is missing:\n${out}")
endif()
run(COMMAND ${CMAKE_COMMAND} -E env --unset=HAPTICFIELD_PLOT_SCRIPT "${bin}/tangible_image"
            "${WORK_DIR}/share_away/data/coffee.png" --maps "${WORK_DIR}/maps_no_script" OUT out)
if(NOT out MATCHES "plot script \\(share/hapticfield/hapticfield_plots.py\\) was not found")
  message(FATAL_ERROR "tangible_image without share/hapticfield/ did not say the plot script is missing:\n${out}")
endif()
message(STATUS "the installed tools ran from ${WORK_DIR}/moved with their own picture and plot script")
