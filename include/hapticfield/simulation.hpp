#pragma once
/// @file simulation.hpp
/// What every simulated arm is built from: the scripted hand that holds the
/// handle and the joint dynamics (inertia, friction, stops).

#include "hapticfield/simulation/joint_dynamics.hpp"
#include "hapticfield/simulation/scripted_hand.hpp"
