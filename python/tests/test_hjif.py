""".hjif haptic media (MPEG-I Haptics) from Python: load, render to numpy against closed forms, export a recorded
run and read it back, the shared sample files, and one clear error for bad files."""
import json
import os
import pathlib

import numpy as np
import pytest

import hapticfield as hf

pytestmark = pytest.mark.skipif(not hasattr(hf, "load_hjif"), reason="built without nlohmann-json (hjif target)")

SHARED = pathlib.Path(os.environ.get("HAPTICFIELD_SHARED_DATA", "")) if os.environ.get("HAPTICFIELD_SHARED_DATA") \
    else pathlib.Path(os.environ.get("HAPTICFIELD_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2])) \
    .parent / "shared" / "data"


def media(bands, modality="Vibrotactile", timescale=1000):
    return {"version": "2023", "profile": "Main", "level": 1, "date": "", "description": "", "timescale": timescale,
            "avatars": [], "syncs": [],
            "perceptions": [{"id": 0, "avatar_id": 0, "description": "", "perception_modality": modality,
                             "reference_devices": [], "effect_library": [],
                             "channels": [{"id": 0, "description": "", "gain": 1.0, "mixing_coefficient": 1.0,
                                           "body_part_mask": 0, "bands": bands}]}]}


def sine_band(f, amplitude, length):
    return {"band_type": "VectorialWave", "lower_frequency_limit": 0, "upper_frequency_limit": 1000,
            "effects": [{"effect_type": "Basis", "position": 0, "phase": 0.0, "base_signal": "Sine",
                         "keyframes": [{"relative_position": 0, "amplitude_modulation": amplitude,
                                        "frequency_modulation": f},
                                       {"relative_position": length, "amplitude_modulation": amplitude,
                                        "frequency_modulation": f}]}]}


def test_a_sine_renders_as_its_closed_form_at_any_rate_and_timescale(tmp_path):
    for timescale, rate in ((1000, 8000.0), (44100, 22050.0), (1000000, 48000.0)):
        path = tmp_path / f"sine{timescale}.hjif"
        path.write_text(json.dumps(media([sine_band(125, 0.5, timescale // 5)], timescale=timescale)))
        y = hf.render_hjif(str(path), rate)
        assert y.shape == (1, int(rate * 0.2) + 1)
        t = np.arange(y.shape[1]) / rate
        np.testing.assert_allclose(y[0], 0.5 * np.sin(2 * np.pi * 125 * t), atol=1e-9)


def test_load_names_channels_and_notes_and_save_round_trips(tmp_path):
    doc = media([sine_band(100, 1.0, 50), {"band_type": "Hologram", "effects": []}], modality="Force")
    doc["vendor"] = {"k": 1}
    src = tmp_path / "a.hjif"
    src.write_text(json.dumps(doc))
    m = hf.load_hjif(str(src))
    assert m.timescale == 1000
    assert m.duration == pytest.approx(0.05)
    assert m.channels[0]["modality"] == "Force"
    assert m.channels[0]["bands"] == ["VectorialWave"]
    assert "kept, not rendered: (top level).vendor" in m.notes
    assert 'skipped: band of unknown band_type "Hologram"' in m.notes
    out = tmp_path / "b.hjif"
    hf.save_hjif(m, str(out))
    assert json.loads(out.read_text())["vendor"] == {"k": 1}
    np.testing.assert_array_equal(hf.load_hjif(str(out)).render(8000.0), m.render(8000.0))


def test_a_recorded_run_exported_reads_back_as_recorded(tmp_path):
    rng = np.random.default_rng()
    force = rng.normal(size=(300, 3))
    contact = np.abs(rng.normal(3.0, 1.0, size=300))
    vibration = 0.4 * np.sin(np.arange(2400) * 0.3)
    m = hf.hjif_from_run(force, contact, vibration, servo_rate=1000.0, vibration_rate=8000.0)
    path = tmp_path / "run.hjif"
    hf.save_hjif(m, str(path))
    back = hf.load_hjif(str(path))
    assert [c["modality"] for c in back.channels] == ["Force", "Force", "Force", "Pressure", "Vibrotactile"]
    at_servo = back.render(1000.0)
    np.testing.assert_allclose(at_servo[:3, :300].T, force, atol=1e-12)
    np.testing.assert_allclose(at_servo[3, :300], contact, atol=1e-12)
    np.testing.assert_allclose(back.render(8000.0)[4, :2400], vibration, atol=1e-12)
    with pytest.raises(ValueError):
        hf.hjif_from_run(np.zeros((0, 3)))


@pytest.mark.parametrize("text, part", [
    ("[" * 1000, "nested deeper than the limit of 32 levels"),
    ('{"perceptions": 3}', "perceptions: expected an array, got number"),
    ('{"perceptions": [', "not JSON"),
])
def test_a_bad_file_is_one_file_error(tmp_path, text, part):
    path = tmp_path / "bad.hjif"
    path.write_text(text)
    with pytest.raises(hf.FileError, match=part):
        hf.load_hjif(str(path))
    with pytest.raises(OSError):
        hf.render_hjif(str(path), 8000.0)
    with pytest.raises(OSError):
        hf.load_hjif(str(tmp_path / "missing.hjif"))


def test_a_bad_rate_is_a_value_error(tmp_path):
    path = tmp_path / "s.hjif"
    path.write_text(json.dumps(media([sine_band(100, 1.0, 50)])))
    with pytest.raises(ValueError):
        hf.render_hjif(str(path), 0.0)


def test_the_shared_samples_render_finite_and_bounded():
    folder = SHARED / "haptics"
    if not folder.is_dir():
        pytest.skip("no shared data folder (set HAPTICFIELD_SHARED_DATA)")
    files = sorted(folder.glob("*.hjif"))
    assert len(files) >= 12
    for f in files:
        y = hf.render_hjif(str(f), 8000.0)
        assert y.ndim == 2 and y.shape[0] >= 1
        assert np.all(np.isfinite(y)) and np.max(np.abs(y)) <= 1.0
