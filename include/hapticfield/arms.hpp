#pragma once
/// @file arms.hpp
/// Every arm family, each with its codec, kinematics, Device and simulated
/// twin (arms/<family>/). A new family is one folder under arms/, its
/// umbrella beside it, and one line here.

#include "hapticfield/arms/dhd.hpp"
#include "hapticfield/arms/falcon.hpp"
#include "hapticfield/arms/force_arm.hpp"
#include "hapticfield/arms/inverse3.hpp"
#include "hapticfield/arms/openhaptics.hpp"
#include "hapticfield/arms/woody.hpp"
