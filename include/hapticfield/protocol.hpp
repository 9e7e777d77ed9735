#pragma once
/// @file protocol.hpp
/// Our wire format, freestanding (no allocation, no exceptions, no I/O): the
/// force-arm report protocol (report ids, codecs, CRC-16) and the stream
/// framer that cuts a byte stream into reports, lines or fixed frames. The
/// host and the firmware core (firmware/) both include it.

#include "hapticfield/protocol/reports.hpp"
#include "hapticfield/protocol/stream_framer.hpp"
