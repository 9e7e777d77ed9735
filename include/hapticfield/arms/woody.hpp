#pragma once
/// @file woody.hpp
/// WoodenHaptics arms: the wire codecs of each generation, the serial woody
/// kinematics, WoodyArm and the simulated woody.

#include "hapticfield/arms/woody/simulated_woody.hpp"
#include "hapticfield/arms/woody/woody_arm.hpp"
#include "hapticfield/arms/woody/woody_codec.hpp"
#include "hapticfield/arms/woody/woody_kinematics.hpp"
