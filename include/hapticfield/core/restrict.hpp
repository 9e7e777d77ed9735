#pragma once
/// @file restrict.hpp
/// HAPTICFIELD_RESTRICT: promises the compiler that a pointer is the only way
/// to its data in a loop, so the loop can be vectorised without alias checks.

#if defined(__GNUC__) || defined(__clang__)
#define HAPTICFIELD_RESTRICT __restrict__
#elif defined(_MSC_VER)
#define HAPTICFIELD_RESTRICT __restrict
#else
#define HAPTICFIELD_RESTRICT
#endif
