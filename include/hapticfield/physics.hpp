#pragma once
/// @file physics.hpp
/// A physics simulation on the other end: the local model a simulator
/// publishes for the servo loop, and the virtual coupling. GLM only
/// (hapticfield::core). The MuJoCo bridge, physics/mujoco_bridge.hpp, needs
/// libmujoco and comes with its own target, hapticfield::mujoco.

#include "hapticfield/physics/local_model.hpp"
#include "hapticfield/physics/virtual_coupling.hpp"
#include "hapticfield/rt/latest_value.hpp"
