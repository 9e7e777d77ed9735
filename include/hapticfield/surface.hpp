#pragma once
/// @file surface.hpp
/// Surfaces: meshes and height fields felt through a proxy (a point or a
/// ball), shapes that move and deform, the brute-force checks of the proxy,
/// and fields laid on them by uv. GLM only (hapticfield::core).

#include "hapticfield/surface/ball_sweep.hpp"
#include "hapticfield/surface/deforming_mesh.hpp"
#include "hapticfield/surface/height_field.hpp"
#include "hapticfield/surface/mesh_bvh.hpp"
#include "hapticfield/surface/mesh_shape.hpp"
#include "hapticfield/surface/moving_shape.hpp"
#include "hapticfield/surface/on_surface.hpp"
#include "hapticfield/surface/posed_shape.hpp"
#include "hapticfield/surface/proxy.hpp"
#include "hapticfield/surface/proxy_check.hpp"
#include "hapticfield/surface/shape.hpp"
#include "hapticfield/surface/triangle_mesh.hpp"
