# The wheel installs offline: writes it (make_wheel.py, the wheel target's command) into WORK_DIR, checks
# its RECORD, installs it with pip --no-index into a fresh venv (--system-site-packages: numpy from the
# system), imports it there, type-checks a use of it with mypy (the stubs found) when mypy is at hand,
# and uninstalls it (RECORD lists every file).
#   -DWHEEL_COMMAND=(make_wheel.py's command, | between arguments) -DWORK_DIR= -DPYTHON= -DSOURCE_DIR=
file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}")

function(run)
  cmake_parse_arguments(R "" "OUT" "COMMAND" ${ARGN})
  execute_process(COMMAND ${R_COMMAND} WORKING_DIRECTORY "${WORK_DIR}" RESULT_VARIABLE rc OUTPUT_VARIABLE out
                  ERROR_VARIABLE err TIMEOUT 120)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}): ${R_COMMAND}\n${out}\n${err}")
  endif()
  if(R_OUT)
    set(${R_OUT} "${out}" PARENT_SCOPE)
  endif()
endfunction()

string(REPLACE "|" ";" command "${WHEEL_COMMAND}")
run(COMMAND ${command} --out "${WORK_DIR}/dist" OUT wheel)
string(STRIP "${wheel}" wheel)
execute_process(COMMAND "${PYTHON}" -c "import sys, sysconfig; print(f'cp{sys.version_info[0]}{sys.version_info[1]}', sysconfig.get_platform().replace('-', '_').replace('.', '_'))"
                OUTPUT_VARIABLE tags OUTPUT_STRIP_TRAILING_WHITESPACE)
separate_arguments(tags)
list(GET tags 0 cp)
list(GET tags 1 platform)
get_filename_component(name "${wheel}" NAME)
if(NOT name MATCHES "^hapticfield-[0-9.]+-${cp}-${cp}-${platform}\\.whl$")
  message(FATAL_ERROR "the wheel ${name} is not tagged ${cp}-${cp}-${platform}")
endif()
run(COMMAND "${PYTHON}" "${SOURCE_DIR}/python/tests/check_wheel.py" "${wheel}")

set(venv "${WORK_DIR}/venv")
run(COMMAND "${PYTHON}" -m venv --system-site-packages "${venv}")
set(env ${CMAKE_COMMAND} -E env --unset=PYTHONPATH PIP_NO_INDEX=1 PIP_DISABLE_PIP_VERSION_CHECK=1)
run(COMMAND ${env} "${venv}/bin/python" -m pip install --no-index "${wheel}")
run(COMMAND ${env} "${venv}/bin/python" -c "print(__import__('sysconfig').get_path('platlib'))" OUT site)
string(STRIP "${site}" site)
run(COMMAND ${env} "${venv}/bin/python" "${SOURCE_DIR}/python/tests/installed_module.py" "${site}" OUT out)
message(STATUS "${out}")
execute_process(COMMAND "${venv}/bin/python" -c "import mypy" RESULT_VARIABLE no_mypy OUTPUT_QUIET ERROR_QUIET)
if(no_mypy EQUAL 0)
  # mypy reads the installed stubs: a wrong type is caught (without them: "missing library stubs")
  file(WRITE "${WORK_DIR}/typed_bad.py" "import hapticfield\nversion: int = hapticfield.__version__\n")
  execute_process(COMMAND ${env} "${venv}/bin/python" -m mypy --no-incremental --cache-dir=/dev/null typed_bad.py
                  WORKING_DIRECTORY "${WORK_DIR}" RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
  if(rc EQUAL 0 OR NOT out MATCHES "Incompatible types in assignment")
    message(FATAL_ERROR "mypy did not check against the installed stubs (${rc}):\n${out}")
  endif()
else()
  message(STATUS "no mypy: the stubs were checked by file only")
endif()
run(COMMAND ${env} "${venv}/bin/python" -m pip uninstall -y hapticfield)
file(GLOB left "${site}/hapticfield*")
if(left)
  message(FATAL_ERROR "pip uninstall left ${left}")
endif()
