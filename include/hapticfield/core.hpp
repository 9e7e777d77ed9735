#pragma once
/// @file core.hpp
/// The core alone: needs GLM and nothing else.

#include "hapticfield/core/any_field.hpp"
#include "hapticfield/core/compose.hpp"
#include "hapticfield/core/constraints.hpp"
#include "hapticfield/core/contact.hpp"
#include "hapticfield/core/error.hpp"
#include "hapticfield/core/field.hpp"
#include "hapticfield/core/live_field.hpp"
#include "hapticfield/core/plane_mapping.hpp"
#include "hapticfield/core/probe.hpp"
#include "hapticfield/core/surface_frame.hpp"
#include "hapticfield/core/vector_math.hpp"
#include "hapticfield/version.hpp"
