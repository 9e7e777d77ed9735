#pragma once
/// @file inverse3.hpp
/// Haply Inverse3 arms: the codec, Inverse3 and the simulated Inverse3.

#include "hapticfield/arms/inverse3/inverse3.hpp"
#include "hapticfield/arms/inverse3/inverse3_codec.hpp"
#include "hapticfield/arms/inverse3/simulated_inverse3.hpp"
