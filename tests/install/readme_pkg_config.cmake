# The README's program ("A field in a loop") built through pkg-config alone from an installed prefix
# (moved after installing), with -Wall -Wextra -Werror: the dependencies' headers come as system
# headers (-isystem), and only the libraries it uses are linked (no videoio, hidapi, libusb, ALSA, libsndfile,
# tinygltf, tinyobjloader or MuJoCo). Then it runs on the example picture; the mujoco and falcon-usb parts
# build and run their consumers with their flags alone.
#   -DBUILD_DIR= -DWORK_DIR= -DSOURCE_DIR= -DCXX= -DPKG_CONFIG=
file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}")

function(run)
  cmake_parse_arguments(R "" "OUT" "COMMAND" ${ARGN})
  execute_process(COMMAND ${R_COMMAND} WORKING_DIRECTORY "${WORK_DIR}" RESULT_VARIABLE rc OUTPUT_VARIABLE out
                  ERROR_VARIABLE err TIMEOUT 300)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}): ${R_COMMAND}\n${out}\n${err}")
  endif()
  if(R_OUT)
    set(${R_OUT} "${out}${err}" PARENT_SCOPE)
  endif()
endfunction()

file(READ "${SOURCE_DIR}/README.md" readme)
string(FIND "${readme}" "## A field in a loop" at)
string(SUBSTRING "${readme}" ${at} -1 readme)
if(NOT readme MATCHES "```cpp\n([^`]*int main\\([^`]*)```")
  message(FATAL_ERROR "README.md: no program under \"A field in a loop\"")
endif()
file(WRITE "${WORK_DIR}/readme_program.cpp" "${CMAKE_MATCH_1}")

run(COMMAND ${CMAKE_COMMAND} --install "${BUILD_DIR}" --prefix "${WORK_DIR}/prefix" --component Unspecified)  # headers, .pc
file(RENAME "${WORK_DIR}/prefix" "${WORK_DIR}/moved")
file(GLOB pc "${WORK_DIR}/moved/*/pkgconfig/hapticfield.pc" "${WORK_DIR}/moved/*/*/pkgconfig/hapticfield.pc")
get_filename_component(pc_dir "${pc}" DIRECTORY)
set(ENV{PKG_CONFIG_PATH} "${pc_dir}")
run(COMMAND "${PKG_CONFIG}" --cflags --libs hapticfield OUT flags)
string(STRIP "${flags}" flags)
message(STATUS "pkg-config --cflags --libs hapticfield: ${flags}")
if(flags MATCHES "-I/usr/include/opencv4")
  message(FATAL_ERROR "OpenCV's headers are not system headers: ${flags}")
endif()
separate_arguments(flags UNIX_COMMAND "${flags}")
run(COMMAND "${CXX}" -Wall -Wextra -Werror -O1 readme_program.cpp ${flags} -o readme_program)

# what it links: the libraries it uses, nothing of the other parts
find_program(READELF NAMES readelf)
if(READELF)
  run(COMMAND "${READELF}" -d readme_program OUT dynamic)
  foreach(other opencv_videoio opencv_highgui opencv_dnn hidapi usb-1.0 asound sndfile tinygltf tinyobjloader mujoco)
    if(dynamic MATCHES "lib${other}")
      message(FATAL_ERROR "the README's program links lib${other}, which it does not use:\n${dynamic}")
    endif()
  endforeach()
endif()

# every part's file gives flags that compile its own header
foreach(part IN ITEMS core video hid falcon-usb vibration-alsa vibration-wav gltf obj hjif mujoco io)
  if(EXISTS "${pc_dir}/hapticfield-${part}.pc")
    run(COMMAND "${PKG_CONFIG}" --cflags --libs hapticfield-${part} OUT part_flags)
    if(NOT part_flags MATCHES "-I[^ ]*/moved/")
      message(FATAL_ERROR "hapticfield-${part}.pc does not follow the moved prefix: ${part_flags}")
    endif()
  endif()
endforeach()

# the simulator bridge and the Falcon's USB link: a program built and run with their flags alone
foreach(part IN ITEMS mujoco falcon-usb)
  string(REPLACE "-" "_" program "consumer_${part}")
  if(EXISTS "${pc_dir}/hapticfield-${part}.pc")
    run(COMMAND "${PKG_CONFIG}" --cflags --libs hapticfield-${part} OUT part_flags)
    string(STRIP "${part_flags}" part_flags)
    message(STATUS "pkg-config --cflags --libs hapticfield-${part}: ${part_flags}")
    separate_arguments(part_flags UNIX_COMMAND "${part_flags}")
    run(COMMAND "${CXX}" -Wall -Wextra -Werror -O1 "${SOURCE_DIR}/tests/consumer/${program}.cpp" ${part_flags}
                -o ${program})
    run(COMMAND "${WORK_DIR}/${program}")
  endif()
endforeach()

run(COMMAND "${WORK_DIR}/readme_program" "${SOURCE_DIR}/examples/data/coffee.png" OUT out)
# What holds on a busy machine: the loop ticked and the safety chain stayed in
# charge. A latch is allowed: a stall of the machine (a late wake, a stale
# state) latches zero force by design.
if(NOT out MATCHES "^[1-9][0-9]* ticks at [0-9.]+ Hz, p99 period [0-9.]+ ms, peak force [0-9.]+ N, latches [0-9]+\n?$")
  message(FATAL_ERROR "the README's program did not run as it says:\n${out}")
endif()
message(STATUS "${out}")
