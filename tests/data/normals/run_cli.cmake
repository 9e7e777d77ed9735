# End-to-end check of the picture_normals command line on a box_demo picture:
#   cmake -DPICTURE_NORMALS=... -DBOX_DEMO=... -DWORK_DIR=... -P run_cli.cmake
file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}")

function(run)
  cmake_parse_arguments(R "" "EXPECT;OUT;ERR" "COMMAND" ${ARGN})
  execute_process(COMMAND ${R_COMMAND} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(R_EXPECT STREQUAL "ok" AND NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}): ${R_COMMAND}\n${out}\n${err}")
  elseif(R_EXPECT STREQUAL "fail" AND rc EQUAL 0)
    message(FATAL_ERROR "should have failed: ${R_COMMAND}\n${out}")
  endif()
  set(${R_OUT} "${out}" PARENT_SCOPE)
  set(${R_ERR} "${err}" PARENT_SCOPE)
endfunction()

run(EXPECT ok OUT out ERR err COMMAND "${BOX_DEMO}" --rotation 45 --trials 1 --out "${WORK_DIR}")
file(STRINGS "${WORK_DIR}/box_45.args" args)
run(EXPECT ok OUT out ERR err COMMAND "${PICTURE_NORMALS}" "${WORK_DIR}/box_45.png" ${args}
    --overlay "${WORK_DIR}/overlay.png" --force-map "${WORK_DIR}/force_map.png" --shading 16 --probes "${WORK_DIR}/box_45_probes.csv" --forces "${WORK_DIR}/forces.csv")
file(WRITE "${WORK_DIR}/normals.txt" "${out}")
string(REGEX MATCHALL "normal: [^\n]*" lines "${out}")
list(LENGTH lines count)
if(NOT count EQUAL 2)
  message(FATAL_ERROR "expected two normal lines, got:\n${out}")
endif()
run(EXPECT ok OUT out ERR err COMMAND "${BOX_DEMO}" --rotation 45 --check "${WORK_DIR}/normals.txt")
message(STATUS "${out}")
# --check - reads the normals from stdin, with the same verdict and lines
execute_process(COMMAND "${BOX_DEMO}" --rotation 45 --check - INPUT_FILE "${WORK_DIR}/normals.txt"
                RESULT_VARIABLE rc OUTPUT_VARIABLE stdin_out ERROR_VARIABLE stdin_err)
if(NOT rc EQUAL 0 OR NOT stdin_out STREQUAL out)
  message(FATAL_ERROR "--check - (stdin) gave ${rc}:\n${stdin_out}\n${stdin_err}\nnot, as from the file:\n${out}")
endif()
execute_process(COMMAND "${BOX_DEMO}" --rotation 45 --check - INPUT_FILE "${WORK_DIR}/box_45.args"
                RESULT_VARIABLE rc OUTPUT_VARIABLE stdin_out ERROR_VARIABLE stdin_err)
if(rc EQUAL 0 OR NOT stdin_err MATCHES "^box_demo: --check: expected two 'normal: nx ny nz' lines in stdin, got 0\n$")
  message(FATAL_ERROR "--check - without normals on stdin gave ${rc}: ${stdin_err}")
endif()
# faces are numbered the same way (from 1, in --face order) by picture_normals
# --verbose and box_demo --check
run(EXPECT ok OUT pn_out ERR pn_err COMMAND "${PICTURE_NORMALS}" "${WORK_DIR}/box_45.png" ${args} --verbose)
string(REGEX MATCHALL "face [0-9]+" verbose_faces "${pn_err}")
string(REGEX MATCHALL "face [0-9]+" check_faces "${out}")
if(NOT verbose_faces STREQUAL "face 1;face 2" OR NOT check_faces STREQUAL verbose_faces)
  message(FATAL_ERROR "faces numbered '${verbose_faces}' by --verbose but '${check_faces}' by --check")
endif()
if(NOT EXISTS "${WORK_DIR}/overlay.png" OR NOT EXISTS "${WORK_DIR}/force_map.png")
  message(FATAL_ERROR "no overlay or force map written")
endif()
file(STRINGS "${WORK_DIR}/forces.csv" forces)
list(LENGTH forces count)
if(NOT count EQUAL 7)
  message(FATAL_ERROR "expected a header and 6 force lines, got ${count} lines")
endif()
list(GET forces 0 header)
if(NOT header STREQUAL "x,y,fx,fy")
  message(FATAL_ERROR "--forces: expected the header line 'x,y,fx,fy', got '${header}'")
endif()
# moving right: climbing the front face resists (fx < 0), descending the side assists (fx > 0)
list(GET forces 1 front_right)
list(GET forces 4 side_right)
if(NOT front_right MATCHES "^[^,]+,[^,]+,-0\\.[0-9]+,0$" OR NOT side_right MATCHES "^[^,]+,[^,]+,0\\.[0-9]+,0$")
  message(FATAL_ERROR "unexpected force signs: '${front_right}', '${side_right}'")
endif()

# without a size the aspect is recovered; without K the focal length is estimated
list(FILTER args EXCLUDE REGEX "^200,200$|^--size$")
run(EXPECT ok OUT out ERR err COMMAND "${PICTURE_NORMALS}" "${WORK_DIR}/box_45.png" ${args})
file(WRITE "${WORK_DIR}/normals_nosize.txt" "${out}")
run(EXPECT ok OUT out ERR err COMMAND "${BOX_DEMO}" --rotation 45 --check "${WORK_DIR}/normals_nosize.txt")
list(FILTER args EXCLUDE REGEX "^1000$|^--focal$")
run(EXPECT ok OUT out ERR err COMMAND "${PICTURE_NORMALS}" "${WORK_DIR}/box_45.png" ${args})
file(WRITE "${WORK_DIR}/normals_nofocal.txt" "${out}")
run(EXPECT ok OUT out ERR err COMMAND "${BOX_DEMO}" --rotation 45 --check "${WORK_DIR}/normals_nofocal.txt")

# K from a calibration file made at twice the picture's size: scaled to fit
file(WRITE "${WORK_DIR}/calibration_2x.yml" "%YAML:1.0
---
image_width: 2048
image_height: 1536
camera_matrix: !!opencv-matrix
   rows: 3
   cols: 3
   dt: d
   data: [ 2000., 0., 1023.5, 0., 2000., 767.5, 0., 0., 1. ]
distortion_coefficients: !!opencv-matrix
   rows: 1
   cols: 5
   dt: d
   data: [ 0., 0., 0., 0., 0. ]
")
file(STRINGS "${WORK_DIR}/box_45.args" args)
list(FILTER args EXCLUDE REGEX "^1000$|^--focal$")
run(EXPECT ok OUT out ERR err COMMAND "${PICTURE_NORMALS}" "${WORK_DIR}/box_45.png" ${args}
    --intrinsics "${WORK_DIR}/calibration_2x.yml")
file(WRITE "${WORK_DIR}/normals_intrinsics.txt" "${out}")
run(EXPECT ok OUT out ERR err COMMAND "${BOX_DEMO}" --rotation 45 --check "${WORK_DIR}/normals_intrinsics.txt")

# bad input: non-zero exit and one line on stderr; the three calibration
# files once crashed or exhausted the tool inside cv::FileStorage
file(WRITE "${WORK_DIR}/decl.xml" "<?xml version=")
file(WRITE "${WORK_DIR}/short.yml" "%YAML:1.\n{ :")
file(WRITE "${WORK_DIR}/typo.yml" "%YAML:1.0\n---\ncamera_matrix: !!opencv-matrix\n   rows: 3\n   cols:k 3\n   dt: d\n   data: [ 800., 0., 320., 0., 800., 240., 0., 0., 1. ]\n")
foreach(bad IN ITEMS "--intrinsics;${WORK_DIR}/decl.xml;--face;0,0 10,0 10,10 0,10"
                     "--intrinsics;${WORK_DIR}/short.yml;--face;0,0 10,0 10,10 0,10"
                     "--intrinsics;${WORK_DIR}/typo.yml;--face;0,0 10,0 10,10 0,10"
                      "--face;1,2 3,4" "--face;0,0 10,10 10,0 0,10" "--face;1,2 3,4 5,6 x,8" "--face;0,0 10,10 20,20 0,30" "--focal;-5;--face;0,0 10,0 10,10 0,10"
                     "--intrinsics;${WORK_DIR}/missing.yml;--face;0,0 10,0 10,10 0,10" "--face;0,0 10,0 10,10 0,10;--probes;x.csv")
  run(EXPECT fail OUT out ERR err COMMAND "${PICTURE_NORMALS}" "${WORK_DIR}/box_45.png" ${bad})
  string(REGEX MATCHALL "\n" newlines "${err}")
  list(LENGTH newlines n)
  if(NOT n EQUAL 1 OR NOT err MATCHES "^picture_normals: ")
    message(FATAL_ERROR "expected one stderr line for '${bad}', got:\n${err}")
  endif()
endforeach()
run(EXPECT fail OUT out ERR err COMMAND "${PICTURE_NORMALS}" "${WORK_DIR}/no_such.png" --face "0,0 10,0 10,10 0,10")

# docs/picture-normals.md states every exit status --help lists (2: usage errors)
run(EXPECT ok OUT help ERR err COMMAND "${PICTURE_NORMALS}" --help)
file(READ "${CMAKE_CURRENT_LIST_DIR}/../../../docs/picture-normals.md" doc)
string(REGEX REPLACE "[ \n]+" " " doc "${doc}")
foreach(status IN ITEMS "0 done" "1 bad input" "2 usage error")
  if(NOT help MATCHES "Exit status:[^\n]*${status}" OR NOT doc MATCHES "Exit status:[^.]*${status}")
    message(FATAL_ERROR "'${status}' is not stated both by picture_normals --help and docs/picture-normals.md")
  endif()
endforeach()
