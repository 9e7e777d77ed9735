# Installs the Python module (cmake --install --component python) into a temporary prefix and
# imports it from there in a fresh interpreter whose PYTHONPATH is the installed site directory only.
#   -DBUILD_DIR= -DWORK_DIR= -DPYTHON= -DSITE=(relative to the prefix) -DSOURCE_DIR=
file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}")

function(run)
  execute_process(COMMAND ${ARGN} WORKING_DIRECTORY "${WORK_DIR}" RESULT_VARIABLE rc OUTPUT_VARIABLE out
                  ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}): ${ARGN}\n${out}\n${err}")
  endif()
  message(STATUS "${out}")
endfunction()

run(${CMAKE_COMMAND} --install "${BUILD_DIR}" --prefix "${WORK_DIR}/prefix" --component python)
set(site "${WORK_DIR}/prefix/${SITE}")
foreach(file __init__.pyi py.typed)
  if(NOT EXISTS "${site}/hapticfield/${file}")
    message(FATAL_ERROR "${site}/hapticfield/${file} was not installed")
  endif()
endforeach()
execute_process(COMMAND ${CMAKE_COMMAND} -E compare_files "${site}/hapticfield/__init__.pyi"
                        "${SOURCE_DIR}/python/stubs/hapticfield/__init__.pyi" RESULT_VARIABLE differ)
if(differ)
  message(FATAL_ERROR "the installed stubs are not the committed ones")
endif()
if(EXISTS "${WORK_DIR}/prefix/include" OR EXISTS "${WORK_DIR}/prefix/bin")
  message(FATAL_ERROR "the python component installed more than the module")
endif()
run(${CMAKE_COMMAND} -E env "PYTHONPATH=${site}" ${PYTHON} -s "${SOURCE_DIR}/python/tests/installed_module.py" "${site}")
