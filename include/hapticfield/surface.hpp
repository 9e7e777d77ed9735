#pragma once
/// @file surface.hpp
/// Surfaces: meshes and height fields felt through a proxy, and fields laid
/// on them by uv. GLM only (hapticfield::core).

#include "hapticfield/surface/height_field.hpp"
#include "hapticfield/surface/mesh_bvh.hpp"
#include "hapticfield/surface/mesh_shape.hpp"
#include "hapticfield/surface/on_surface.hpp"
#include "hapticfield/surface/posed_shape.hpp"
#include "hapticfield/surface/proxy.hpp"
#include "hapticfield/surface/shape.hpp"
#include "hapticfield/surface/triangle_mesh.hpp"
