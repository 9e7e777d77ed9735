// .hjif haptic media (MPEG-I Haptics) in Python: load_hjif, save_hjif, render_hjif, hjif_from_run.
#include "field.hpp"

#include <hapticfield/io/hjif.hpp>
#include <hapticfield/material/band_synthesis.hpp>
#include <hapticfield/material/haptic_recording.hpp>

#include <pybind11/stl.h>

#include <cmath>
#include <cstring>
#include <string>
#include <vector>

namespace hapticfield::python {

namespace {

/// A loaded or built media with the notes of its reading.
struct PyHjif {
  material::HapticMedia media;
  std::vector<std::string> notes;
};

/// channels x samples, float64.
py::array_t<double> render_array(const material::HapticMedia& m, double rate) {
  material::RenderedMedia r;
  {
    py::gil_scoped_release release;
    r = material::render_media(m, rate);
  }
  const auto rows = static_cast<py::ssize_t>(r.channels.size());
  const auto cols = static_cast<py::ssize_t>(r.channels.empty() ? 0 : r.channels.front().size());
  py::array_t<double> out({rows, cols});
  for (py::ssize_t c = 0; c < rows; ++c)
    std::memcpy(out.mutable_data(c, 0), r.channels[static_cast<std::size_t>(c)].data(),
                static_cast<std::size_t>(cols) * sizeof(double));
  return out;
}

double checked_rate(double rate) {
  if (!(rate >= material::min_render_rate && rate <= material::max_render_rate))
    throw py::value_error("rate must be within [1, 384000] Hz");
  return rate;
}

py::list channel_list(const material::HapticMedia& m) {
  py::list out;
  for (const material::Perception& p : m.perceptions)
    for (const material::Channel& c : p.channels) {
      py::list bands;
      for (const material::Band& b : c.bands)
        bands.append(material::band_type_name(b.type));
      py::dict d;
      d["perception"] = p.id;
      d["modality"] = p.modality;
      d["channel"] = c.id;
      d["description"] = c.description;
      d["gain"] = c.gain;
      d["bands"] = bands;
      out.append(d);
    }
  return out;
}

}  // namespace

void bind_hjif(py::module_& m) {
  py::class_<PyHjif>(m, "HapticMedia",
                     "An MPEG-I Haptics media (.hjif): perceptions, channels, bands, effects, keyframes. "
                     "docs/hjif.md lists every field and whether it is rendered, kept or skipped.")
      .def_property_readonly(
          "timescale", [](const PyHjif& h) { return h.media.timescale; }, "ticks per second of every position")
      .def_property_readonly(
          "duration", [](const PyHjif& h) { return material::media_duration(h.media); }, "length [s]")
      .def_property_readonly(
          "channels", [](const PyHjif& h) { return channel_list(h.media); },
          "one dict per channel in file order: perception, modality, channel, description, gain, bands")
      .def_property_readonly(
          "notes", [](const PyHjif& h) { return h.notes; }, "what the reader kept without rendering or skipped")
      .def(
          "render", [](const PyHjif& h, double rate) { return render_array(h.media, checked_rate(rate)); },
          py::arg("rate"), "every channel at rate [Hz]: a channels x samples float64 array (sample i at i / rate)")
      .def("__repr__", [](const PyHjif& h) {
        std::size_t n = 0;
        for (const auto& p : h.media.perceptions)
          n += p.channels.size();
        return "HapticMedia(" + std::to_string(n) + " channel(s), " +
               std::to_string(material::media_duration(h.media)) + " s)";
      });

  m.def(
      "load_hjif",
      [](const std::string& path) {
        io::HjifFile f = io::load_hjif(path);
        return PyHjif{std::move(f.media), std::move(f.notes)};
      },
      py::arg("path"),
      "Reads a .hjif file. Raises FileError (an OSError) naming the file and the JSON path for a missing file, text "
      "that is not JSON, a wrong type or a passed limit (64 MiB, nesting 32, 8,000,000 values, 4,000,000 elements "
      "per array, 1 MiB per string).");
  m.def(
      "save_hjif", [](const PyHjif& h, const std::string& path) { io::save_hjif(h.media, path); }, py::arg("media"),
      py::arg("path"), "Writes the media as .hjif, laid out as the MPEG reference software writes and reads it.");
  m.def(
      "render_hjif",
      [](const std::string& path, double rate) {
        const double r = checked_rate(rate);
        return render_array(io::load_hjif(path).media, r);
      },
      py::arg("path"), py::arg("rate") = 8000.0,
      "Renders every channel of a .hjif file at rate [Hz]: a channels x samples float64 array, channels in file "
      "order (as hjif_render's WAV).");
  m.def(
      "hjif_from_run",
      [](const Array& force, const std::optional<Array>& contact, const std::optional<Array>& vibration,
         double servo_rate, double vibration_rate, double full_scale_force) {
        material::RecordedRun run;
        run.servo_rate = servo_rate;
        run.vibration_rate = vibration_rate;
        run.full_scale_force = full_scale_force;
        const py::ssize_t n = rows_of(force, 3, "force");
        for (py::ssize_t i = 0; i < n; ++i)
          run.force.push_back({force.at(i, 0), force.at(i, 1), force.at(i, 2)});
        if (contact) {
          const py::ssize_t k = rows_of(*contact, 0, "contact");
          for (py::ssize_t i = 0; i < k; ++i)
            run.contact.push_back(contact->data()[i]);
        }
        if (vibration) {
          const py::ssize_t k = rows_of(*vibration, 0, "vibration");
          for (py::ssize_t i = 0; i < k; ++i)
            run.vibration.push_back(vibration->data()[i]);
        }
        try {
          return PyHjif{material::media_from_run(run), {}};
        } catch (const std::invalid_argument& e) {
          throw py::value_error(e.what());
        }
      },
      py::arg("force"), py::arg("contact") = py::none(), py::arg("vibration") = py::none(),
      py::arg("servo_rate") = 1000.0, py::arg("vibration_rate") = 8000.0, py::arg("full_scale_force") = 0.0,
      "A recorded run as a HapticMedia: force (N x 3) [N] at servo_rate [Hz] as a Force perception, contact (N) "
      "|Fc| [N] as a Pressure perception, vibration (M) at vibration_rate [Hz] as a Vibrotactile perception; "
      "full_scale_force [N] (0: the largest recorded) is each force channel's gain.");
}

}  // namespace hapticfield::python
