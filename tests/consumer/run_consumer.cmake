# Builds and runs the consumer project in tests/consumer against this tree.
#   MODE=find_package     install into a temporary prefix, then find_package
#   MODE=add_subdirectory the consumer adds the source tree directly
file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}")

function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}): ${ARGN}\n${out}\n${err}")
  endif()
endfunction()

set(consumer_args -S "${SOURCE_DIR}/tests/consumer" -B "${WORK_DIR}/build" -DCMAKE_BUILD_TYPE=Release
                  -DHAPTICFIELD_CONSUMER_MODE=${MODE})
if(MODE STREQUAL "find_package")
  run(${CMAKE_COMMAND} --install "${BUILD_DIR}" --prefix "${WORK_DIR}/prefix")
  list(APPEND consumer_args "-DCMAKE_PREFIX_PATH=${WORK_DIR}/prefix")
elseif(MODE STREQUAL "add_subdirectory")
  list(APPEND consumer_args "-DHAPTICFIELD_SOURCE=${SOURCE_DIR}")
else()
  message(FATAL_ERROR "unknown MODE '${MODE}'")
endif()
run(${CMAKE_COMMAND} ${consumer_args})
run(${CMAKE_COMMAND} --build "${WORK_DIR}/build")
run("${WORK_DIR}/build/consumer_core")
run("${WORK_DIR}/build/consumer_hatt" "${SOURCE_DIR}/tests/data/hatt/Models_Toolkit 1kHz ARMA.xml")
run("${WORK_DIR}/build/consumer_image" "${SOURCE_DIR}/examples/data/coffee.png")
file(MAKE_DIRECTORY "${WORK_DIR}/frames")
run("${WORK_DIR}/build/consumer_video" "${WORK_DIR}/frames")
if(MODE STREQUAL "find_package")
  # The pkg-config file must name the installed headers.
  file(GLOB pc "${WORK_DIR}/prefix/*/pkgconfig/hapticfield.pc" "${WORK_DIR}/prefix/*/*/pkgconfig/hapticfield.pc")
  if(NOT pc)
    message(FATAL_ERROR "hapticfield.pc was not installed")
  endif()
endif()
message(STATUS "consumer (${MODE}) built and ran")
