#pragma once
/// @file vibration.hpp
/// Vibration at audio rate beside the force loop (link hapticfield::vibration):
/// tap(field, ring) pushes one contact sample per servo tick; the audio
/// side drains the ring without waiting, plays the contact out behind the
/// servo clock, runs the sources (HaTT models at their own rate, tones,
/// recorded signals, any texture) and writes to a sink.
///
///   vibration/contact_sample.hpp  ContactSample, ContactState, ContactRing
///   vibration/tap.hpp             tap(field, ring): the servo side
///   vibration/playout.hpp         ContactPlayout: drain, delay, interpolate
///   vibration/sources.hpp         ToneSource, SignalSource, TextureSource
///   vibration/hatt_source.hpp     HattSource: a HaTT model set at its own rate
///   vibration/renderer.hpp        VibrationRenderer: the audio callback
///   vibration/stream.hpp          NullSink, VibrationStream (the audio thread)
///
/// Not included here, one header per outside library, each with its target:
///   vibration/alsa_sink.hpp       AlsaSink (ALSA, hapticfield::vibration_alsa)
///   vibration/wav_sink.hpp        WavSink, read_wav (libsndfile, hapticfield::vibration_wav)

#include "hapticfield/vibration/contact_sample.hpp"
#include "hapticfield/vibration/hatt_source.hpp"
#include "hapticfield/vibration/playout.hpp"
#include "hapticfield/vibration/renderer.hpp"
#include "hapticfield/vibration/sources.hpp"
#include "hapticfield/vibration/stream.hpp"
#include "hapticfield/vibration/tap.hpp"
