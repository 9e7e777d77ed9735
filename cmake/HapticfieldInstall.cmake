# Install rules: headers, one export set per component (so a consumer that
# uses only the core never needs OpenCV, pugixml or hidapi), a Config file that finds
# each component's dependencies, a version file and a pkg-config file.
include(CMakePackageConfigHelpers)

set(HAPTICFIELD_CMAKE_DIR "${CMAKE_INSTALL_LIBDIR}/cmake/hapticfield")

install(DIRECTORY "${PROJECT_SOURCE_DIR}/include/hapticfield" DESTINATION "${CMAKE_INSTALL_INCLUDEDIR}")

install(TARGETS hapticfield_core EXPORT hapticfieldCoreTargets)
install(EXPORT hapticfieldCoreTargets NAMESPACE hapticfield:: DESTINATION "${HAPTICFIELD_CMAKE_DIR}")
if(HAPTICFIELD_HAS_PUGIXML)
  install(TARGETS hapticfield_hatt EXPORT hapticfieldHattTargets)
  install(EXPORT hapticfieldHattTargets NAMESPACE hapticfield:: DESTINATION "${HAPTICFIELD_CMAKE_DIR}")
endif()
if(HAPTICFIELD_HAS_IMAGE)
  install(TARGETS hapticfield_image EXPORT hapticfieldImageTargets)
  install(EXPORT hapticfieldImageTargets NAMESPACE hapticfield:: DESTINATION "${HAPTICFIELD_CMAKE_DIR}")
endif()
if(HAPTICFIELD_HAS_VIDEO)
  install(TARGETS hapticfield_video EXPORT hapticfieldVideoTargets)
  install(EXPORT hapticfieldVideoTargets NAMESPACE hapticfield:: DESTINATION "${HAPTICFIELD_CMAKE_DIR}")
endif()
if(HAPTICFIELD_HAS_HID)
  install(TARGETS hapticfield_hid EXPORT hapticfieldHidTargets)
  install(EXPORT hapticfieldHidTargets NAMESPACE hapticfield:: DESTINATION "${HAPTICFIELD_CMAKE_DIR}")
endif()
if(HAPTICFIELD_HAS_GLTF)
  install(TARGETS hapticfield_gltf EXPORT hapticfieldGltfTargets)
  install(EXPORT hapticfieldGltfTargets NAMESPACE hapticfield:: DESTINATION "${HAPTICFIELD_CMAKE_DIR}")
endif()
if(HAPTICFIELD_HAS_OBJ)
  install(TARGETS hapticfield_obj EXPORT hapticfieldObjTargets)
  install(EXPORT hapticfieldObjTargets NAMESPACE hapticfield:: DESTINATION "${HAPTICFIELD_CMAKE_DIR}")
endif()
if(HAPTICFIELD_HAS_IO)
  install(TARGETS hapticfield_io EXPORT hapticfieldIoTargets)
  install(EXPORT hapticfieldIoTargets NAMESPACE hapticfield:: DESTINATION "${HAPTICFIELD_CMAKE_DIR}")
endif()

install(TARGETS hapticfield_vibration EXPORT hapticfieldVibrationTargets)
install(EXPORT hapticfieldVibrationTargets NAMESPACE hapticfield:: DESTINATION "${HAPTICFIELD_CMAKE_DIR}")
if(HAPTICFIELD_HAS_ALSA)
  install(TARGETS hapticfield_vibration_alsa EXPORT hapticfieldVibrationAlsaTargets)
  install(EXPORT hapticfieldVibrationAlsaTargets NAMESPACE hapticfield:: DESTINATION "${HAPTICFIELD_CMAKE_DIR}")
endif()
if(HAPTICFIELD_HAS_SNDFILE)
  install(TARGETS hapticfield_vibration_wav EXPORT hapticfieldVibrationWavTargets)
  install(EXPORT hapticfieldVibrationWavTargets NAMESPACE hapticfield:: DESTINATION "${HAPTICFIELD_CMAKE_DIR}")
endif()

configure_package_config_file(
  "${PROJECT_SOURCE_DIR}/cmake/hapticfieldConfig.cmake.in"
  "${PROJECT_BINARY_DIR}/hapticfieldConfig.cmake"
  INSTALL_DESTINATION "${HAPTICFIELD_CMAKE_DIR}")
write_basic_package_version_file(
  "${PROJECT_BINARY_DIR}/hapticfieldConfigVersion.cmake"
  COMPATIBILITY SameMinorVersion ARCH_INDEPENDENT)
install(FILES "${PROJECT_BINARY_DIR}/hapticfieldConfig.cmake"
              "${PROJECT_BINARY_DIR}/hapticfieldConfigVersion.cmake"
        DESTINATION "${HAPTICFIELD_CMAKE_DIR}")

set(HAPTICFIELD_PC_REQUIRES "glm")
if(HAPTICFIELD_HAS_PUGIXML)
  string(APPEND HAPTICFIELD_PC_REQUIRES " pugixml")
endif()
if(HAPTICFIELD_HAS_IMAGE)
  string(APPEND HAPTICFIELD_PC_REQUIRES " opencv4")
endif()
if(HAPTICFIELD_HAS_HID)
  string(APPEND HAPTICFIELD_PC_REQUIRES " hidapi-hidraw")
endif()
if(HAPTICFIELD_HAS_ALSA)
  string(APPEND HAPTICFIELD_PC_REQUIRES " alsa")
endif()
if(HAPTICFIELD_HAS_SNDFILE)
  string(APPEND HAPTICFIELD_PC_REQUIRES " sndfile")
endif()
if(HAPTICFIELD_HAS_GLTF)
  string(APPEND HAPTICFIELD_PC_REQUIRES " tinygltf")
endif()
if(HAPTICFIELD_HAS_OBJ)
  string(APPEND HAPTICFIELD_PC_REQUIRES " tinyobjloader_double")
endif()
# Relocatable: the prefix is found from the .pc file's own place (${pcfiledir}), so the installed
# tree works wherever it is installed (cmake --install --prefix P) or moved to afterwards.
set(HAPTICFIELD_PC_DIR "${CMAKE_INSTALL_DATAROOTDIR}/pkgconfig")
if(IS_ABSOLUTE "${HAPTICFIELD_PC_DIR}" OR IS_ABSOLUTE "${CMAKE_INSTALL_INCLUDEDIR}")
  set(HAPTICFIELD_PC_PREFIX "${CMAKE_INSTALL_PREFIX}")  # an absolute layout cannot move
else()
  file(RELATIVE_PATH HAPTICFIELD_PC_UP "/hapticfield_prefix/${HAPTICFIELD_PC_DIR}" "/hapticfield_prefix")
  string(REGEX REPLACE "/$" "" HAPTICFIELD_PC_UP "${HAPTICFIELD_PC_UP}")
  set(HAPTICFIELD_PC_PREFIX "\${pcfiledir}/${HAPTICFIELD_PC_UP}")
endif()
configure_file("${PROJECT_SOURCE_DIR}/cmake/hapticfield.pc.in" "${PROJECT_BINARY_DIR}/hapticfield.pc" @ONLY)
install(FILES "${PROJECT_BINARY_DIR}/hapticfield.pc" DESTINATION "${HAPTICFIELD_PC_DIR}")
