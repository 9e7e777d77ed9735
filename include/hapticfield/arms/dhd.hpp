#pragma once
/// @file dhd.hpp
/// Force Dimension arms through the DHD SDK, loaded at run time: the DHD
/// declarations and DhdDevice.

#include "hapticfield/arms/dhd/dhd_api.hpp"
#include "hapticfield/arms/dhd/dhd_device.hpp"
