#pragma once
/// @file always_inline.hpp
/// HAPTICFIELD_ALWAYS_INLINE: asks the compiler to inline a small function
/// into every caller, where its own heuristics would stop (a hot test called
/// from two traversals, a kernel's inner step). After the declarator of a
/// function or a lambda's parameter list.

#if defined(__GNUC__) || defined(__clang__)
#define HAPTICFIELD_ALWAYS_INLINE __attribute__((always_inline))
#else
#define HAPTICFIELD_ALWAYS_INLINE
#endif
