#pragma once
/// @file io.hpp
/// File readers, never used in a tick: meshes (glTF through tinygltf, OBJ
/// through tinyobjloader, STL) into a TriangleMesh, and height maps
/// (pictures, 16-bit and float depth maps through OpenCV) into a
/// HeightGrid. Readers only: compositions built on what they read
/// (picture_relief(), textured_model()) stand in scenes/. Needs the CMake
/// target hapticfield::io; each header alone needs less
/// (docs/mesh-files.md, docs/surfaces.md).

#include "hapticfield/io/gltf.hpp"
#include "hapticfield/io/height_grid.hpp"
#include "hapticfield/io/height_map.hpp"
#include "hapticfield/io/load_mesh.hpp"
#include "hapticfield/io/mesh_read.hpp"
#include "hapticfield/io/obj.hpp"
#include "hapticfield/io/stl.hpp"
