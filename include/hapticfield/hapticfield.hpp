#pragma once
/// @file hapticfield.hpp
/// Umbrella header: the component umbrellas whose dependencies every
/// install has (GLM, OpenCV core/imgproc/imgcodecs, pugixml for the HaTT
/// files): core, image, kernels, texture (with the HaTT reader), normals,
/// surface, material, physics (not the MuJoCo bridge), device, protocol,
/// transport (recording and replay), simulation, arms, servo, vibration.
///
/// Left out, each to be included by name, because it needs a library or a
/// target a user may not have, or is no component:
///  - io.hpp (mesh and height-map readers: tinygltf, tinyobjloader; target
///    hapticfield::io), io/hjif.hpp and io/gltf_haptic_material.hpp, and
///    scenes.hpp (compositions over what io/ reads);
///  - video.hpp (OpenCV videoio);
///  - transport/hid_transport.hpp (hidapi), transport/serial_*.hpp, the
///    arms' *_door.hpp, arms/falcon/falcon_libusb.hpp (libusb-1.0) and the
///    device front door (devices/open_device.hpp, device/any_device.hpp,
///    device/device_family.hpp), which opens all of them;
///  - vibration/alsa_sink.hpp (ALSA) and vibration/wav_sink.hpp
///    (libsndfile);
///  - physics/mujoco_bridge.hpp (libmujoco; target hapticfield::mujoco);
///  - texture/image_maps.hpp (OpenCV helpers for image-driven textures);
///  - setup and analysis code that allocates: servo/tick_budget.hpp (it may
///    replace operator new), texture/psd.hpp;
///  - firmware/ (the device side, built for a microcontroller);
///  - offline.hpp (deprecated; its headers come with kernels, texture and
///    normals).

#include "hapticfield/arms.hpp"
#include "hapticfield/core.hpp"
#include "hapticfield/device.hpp"
#include "hapticfield/image.hpp"
#include "hapticfield/kernels.hpp"
#include "hapticfield/material.hpp"
#include "hapticfield/normals.hpp"
#include "hapticfield/physics.hpp"
#include "hapticfield/protocol.hpp"
#include "hapticfield/servo.hpp"
#include "hapticfield/simulation.hpp"
#include "hapticfield/surface.hpp"
#include "hapticfield/texture.hpp"
#include "hapticfield/texture/hatt.hpp"
#include "hapticfield/transport.hpp"
#include "hapticfield/vibration.hpp"
