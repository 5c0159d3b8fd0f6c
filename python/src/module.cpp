// SPDX-License-Identifier: MIT
// strike._strike: the C++ engine for Python (pybind11). The same library functions as the CLI
// (tools/cli/cmd_modes.cpp, cmd_hit.cpp, cmd_render.cpp), so the same inputs give the same bytes.
// Python-facing argument checks and defaults live in strike/__init__.py; this layer converts
// types, releases the GIL around the work, and turns an Error into an exception carrying its
// message unchanged (it names the file, key and value).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <memory>
#include <optional>
#include <string>

#include "strike/audio/audio.hpp"
#include "strike/bank/bank.hpp"
#include "strike/precompute/error_estimate.hpp"
#include "strike/scene/hit.hpp"
#include "strike/precompute/materials.hpp"
#include "strike/precompute/precompute.hpp"
#include "strike/scene/render.hpp"
#include "strike/scene/render_session.hpp"
#include "strike/scene/scene.hpp"
#include "strike/precompute/similar_bank.hpp"

namespace py = pybind11;

namespace strike {
namespace {

/// Bad input (the CLI's exit code 1) raises strike.InputError (a ValueError), a bug RuntimeError.
/// Called with the GIL held.
[[noreturn]] void raise(const Error& error) {
  if (error.kind == ErrorKind::BadInput) {
    py::object type = py::module_::import("strike._strike").attr("InputError");
    PyErr_SetString(type.ptr(), error.message.c_str());
    throw py::error_already_set();
  }
  throw std::runtime_error("internal error: " + error.message);
}

template <class T>
T take(Result<T>&& result) {
  if (!result) raise(result.error());
  return std::move(result.value());
}

void check(const Status& status) {
  if (!status) raise(status.error());
}

py::array_t<double> doubles(const std::vector<double>& values) {
  return py::array_t<double>(static_cast<py::ssize_t>(values.size()), values.data());
}

py::array_t<float> samples(const AudioBuffer& audio) {
  if (audio.channels <= 1)
    return py::array_t<float>(static_cast<py::ssize_t>(audio.samples.size()), audio.samples.data());
  return py::array_t<float>({static_cast<py::ssize_t>(audio.frames()), static_cast<py::ssize_t>(audio.channels)},
                            audio.samples.data());
}

SampleEncoding encodingNamed(const std::string& format) {
  if (format == "pcm16") return SampleEncoding::Pcm16;
  if (format == "pcm24") return SampleEncoding::Pcm24;
  if (format == "float") return SampleEncoding::Float32;
  raise(badInput("format = '" + format + "' (expected pcm16, pcm24 or float)"));
}

std::string hex64(uint64_t value) {
  char text[17];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(value));
  return text;
}

py::dict materialDict(const Material& m) {
  py::dict d;
  d["name"] = m.name;
  d["youngs_pa"] = m.youngs_pa;
  d["poisson"] = m.poisson;
  d["density_kg_m3"] = m.density_kg_m3;
  d["rayleigh_stiffness"] = m.rayleigh_stiffness;
  d["rayleigh_mass"] = m.rayleigh_mass;
  return d;
}

/// A str or os.PathLike argument as a path string.
std::string pathOf(const py::object& path) {
  return py::str(py::module_::import("os").attr("fspath")(path)).cast<std::string>();
}

using BankPtr = std::shared_ptr<ModeBank>;

BankPtr computeModes(const std::string& mesh, const Material& material, int order, double size_m, double max_freq_hz,
                     int max_modes, int64_t max_tets, std::optional<bool> error_estimate,
                     std::optional<double> tolerance, bool transfer) {
  PrecomputeSettings settings;
  settings.mesh_spec = mesh;
  settings.material = material;
  settings.order = order;
  settings.target_edge_m = size_m;
  settings.max_freq_hz = max_freq_hz;
  settings.max_modes = max_modes;
  settings.max_tets = max_tets;
  settings.acoustic_transfer = transfer;  // default on, as `strike modes` (--no-transfer)
  // The CLI's default (cmd_modes.cpp): on when the mesh can be coarsened.
  settings.error_estimate = error_estimate.value_or(canRemesh(mesh));
  std::optional<Result<PrecomputeResult>> result;
  {
    py::gil_scoped_release released;
    if (tolerance) {
      Result<ToleranceResult> chosen = computeModeBankToTolerance(settings, *tolerance);
      if (chosen)
        result.emplace(std::move(chosen->chosen));
      else
        result.emplace(chosen.error());
    } else {
      result.emplace(computeModeBank(settings));
    }
  }
  return std::make_shared<ModeBank>(take(std::move(*result)).bank);
}

struct PyRenderResult {
  RenderResult result;
  std::string scene_path;
};

py::dict reportDict(const PyRenderResult& r) {
  const RenderReport& s = r.result.report;
  py::dict d;
  d["scene"] = r.scene_path;
  d["rate"] = r.result.audio.sample_rate_hz;
  d["frames"] = r.result.audio.frames();
  d["channels"] = r.result.audio.channels;
  d["bodies"] = r.result.body_names;
  py::list banks;
  for (size_t i = 0; i < r.result.banks.size(); ++i) {
    const BodyBank& b = r.result.banks[i];
    py::dict entry;
    entry["body"] = r.result.body_names[i];
    entry["cache_key"] = b.cache_key ? py::object(py::str(hex64(b.cache_key))) : py::object(py::none());
    entry["given"] = b.given_path.empty() ? py::object(py::none()) : py::object(py::str(b.given_path));
    entry["sounded"] = b.sounded;
    entry["transfer_key"] = b.transfer_key ? py::object(py::str(hex64(b.transfer_key))) : py::object(py::none());
    banks.append(entry);
  }
  d["banks"] = banks;
  d["objects"] = s.objects;
  d["objects_struck"] = s.objects_struck;
  d["objects_sounded"] = s.objects_sounded;
  d["objects_inaudible"] = s.objects_inaudible;
  d["banks_given"] = s.banks_given;
  d["banks_cached"] = s.banks_cached;
  d["banks_computed"] = s.banks_computed;
  d["banks_shared"] = s.banks_shared;
  d["banks_scaled"] = s.banks_scaled;
  d["transfers_solved"] = s.transfers_solved;
  d["transfers_cached"] = s.transfers_cached;
  d["transfers_shared"] = s.transfers_shared;
  d["events"] = s.events;
  d["impacts"] = s.impacts;
  d["sustained_contacts"] = s.sustained_contacts;
  d["load_changes"] = s.load_changes;
  d["load_holds"] = s.load_holds;
  d["continuous_contacts"] = s.continuous_contacts;
  d["continuous_dropped"] = s.continuous_dropped;
  d["modes_total"] = s.modes_total;
  d["modes_out_of_band"] = s.modes_out_of_band;
  d["mode_samples"] = s.mode_samples;
  d["max_active_modes"] = s.max_active_modes;
  d["peak"] = s.peak;
  d["clipped_samples"] = s.clipped_samples;
  py::dict seconds;
  seconds["load"] = s.load_seconds;
  seconds["simulate"] = s.simulate_seconds;
  seconds["modes"] = s.precompute_seconds;
  seconds["synthesize"] = s.synthesize_seconds;
  seconds["total"] = s.total_seconds;
  seconds["saved_by_cache"] = s.precompute_saved_seconds;
  seconds["transfers_saved_by_cache"] = s.transfer_saved_seconds;
  d["seconds"] = seconds;
  return d;
}

/// Contact events as a numpy structured array (one row per event, the CSV's columns), filled a
/// column at a time (a row at a time through the Python API costs ~8 us per event).
py::object eventsArray(const RenderResult& r) {
  py::module_ np = py::module_::import("numpy");
  const std::vector<ContactEvent>& events = r.events;
  const py::ssize_t n = static_cast<py::ssize_t>(events.size());
  py::list fields;
  py::dict columns;
  auto scalar = [&](const char* name, auto get) {
    using T = decltype(get(events[0]));
    py::array_t<T> column(n);
    auto out = column.template mutable_unchecked<1>();
    for (py::ssize_t i = 0; i < n; ++i) out(i) = get(events[static_cast<size_t>(i)]);
    fields.append(py::make_tuple(name, column.dtype()));
    columns[name] = column;
  };
  auto vector3 = [&](const char* name, std::array<double, 3> ContactEvent::*member) {
    py::array_t<double> column({n, py::ssize_t(3)});
    auto out = column.mutable_unchecked<2>();
    for (py::ssize_t i = 0; i < n; ++i)
      for (py::ssize_t a = 0; a < 3; ++a) out(i, a) = (events[static_cast<size_t>(i)].*member)[static_cast<size_t>(a)];
    fields.append(py::make_tuple(name, "f8", py::make_tuple(3)));
    columns[name] = column;
  };
  auto body = [](uint32_t index) { return index == kGroundBody ? int32_t(-1) : static_cast<int32_t>(index); };
  scalar("time_s", [](const ContactEvent& e) { return e.time_s; });
  scalar("step_time_s", [](const ContactEvent& e) { return e.step_time_s; });
  scalar("body_a", [&](const ContactEvent& e) { return body(e.body_a); });
  scalar("body_b", [&](const ContactEvent& e) { return body(e.body_b); });
  scalar("new_contact", [](const ContactEvent& e) { return e.new_contact; });
  scalar("normal_speed_m_s", [](const ContactEvent& e) { return e.normal_speed_m_s; });
  scalar("normal_impulse_n_s", [](const ContactEvent& e) { return e.normal_impulse_n_s; });
  scalar("friction_impulse_n_s", [](const ContactEvent& e) { return e.friction_impulse_n_s; });
  vector3("point_world", &ContactEvent::point_world);
  vector3("normal_world", &ContactEvent::normal_world);
  vector3("point_a_mesh", &ContactEvent::point_a_mesh);
  vector3("point_b_mesh", &ContactEvent::point_b_mesh);
  vector3("impulse_on_a_mesh", &ContactEvent::impulse_on_a_mesh);
  // Contact state (docs/contact.md), appended after the fields above.
  scalar("normal_force_n", [](const ContactEvent& e) { return e.normal_force_n; });
  vector3("slip_velocity_m_s", &ContactEvent::slip_velocity_m_s);
  scalar("rolling_speed_m_s", [](const ContactEvent& e) { return e.rolling_speed_m_s; });
  scalar("track_speed_a_m_s", [](const ContactEvent& e) { return e.track_speed_a_m_s; });
  scalar("track_speed_b_m_s", [](const ContactEvent& e) { return e.track_speed_b_m_s; });
  scalar("patch_radius_m", [](const ContactEvent& e) { return e.patch_radius_m; });
  // The CSV's motion word ("rest", "rolling", "sliding", "rolling+sliding") as a short string.
  py::list motion;
  for (const ContactEvent& e : events) motion.append(contactMotion(e));
  fields.append(py::make_tuple("motion", "U15"));
  columns["motion"] = motion;
  py::object array = np.attr("zeros")(n, np.attr("dtype")(fields));
  for (auto item : columns) array[item.first] = item.second;
  return array;
}

PyRenderResult renderParsed(Result<Scene>&& parsed, double rate, double duration, double gain,
                            const std::string& cache_dir, int64_t max_tets, int64_t max_events, bool similar,
                            bool transfer, std::shared_ptr<RenderSession> session, unsigned solve_threads,
                            const std::string& output, const std::string& hrtf) {
  Scene scene = take(std::move(parsed));
  RenderSettings settings;
  const std::optional<OutputFormat> format = parseOutputFormat(output);
  if (!format) raise(badInput("output = '" + output + "' (must be mono, stereo, binaural, ambix1, ambix2 or ambix3)"));
  settings.output_format = *format;
  if (!hrtf.empty() && *format != OutputFormat::Binaural)
    raise(badInput("hrtf = '" + hrtf + "' needs output = 'binaural'"));
  settings.hrtf_file = hrtf;
  settings.sample_rate_hz = rate;
  settings.duration_s = duration;
  settings.gain = gain;
  settings.cache_dir = cache_dir;
  settings.max_tets = max_tets;
  settings.max_events = static_cast<size_t>(max_events);
  settings.similar_reuse = similar;
  settings.acoustic_transfer = transfer;
  settings.session = session.get();  // `session` holds it through the render
  settings.solve_threads = solve_threads;
  std::optional<Result<RenderResult>> result;
  {
    py::gil_scoped_release released;
    result.emplace(renderScene(scene, settings));
  }
  return PyRenderResult{take(std::move(*result)), scene.path};
}

/// A material from the dict the Python layer builds (strike/__init__.py resolves names).
Material materialFrom(const py::dict& material) {
  Material mat;
  mat.name = material["name"].cast<std::string>();
  mat.youngs_pa = material["youngs_pa"].cast<double>();
  mat.poisson = material["poisson"].cast<double>();
  mat.density_kg_m3 = material["density_kg_m3"].cast<double>();
  mat.rayleigh_stiffness = material["rayleigh_stiffness"].cast<double>();
  mat.rayleigh_mass = material["rayleigh_mass"].cast<double>();
  return mat;
}

}  // namespace
}  // namespace strike

PYBIND11_MODULE(_strike, m) {
  using namespace strike;
  m.doc() = "The Strike engine (C++). Use the `strike` package, which wraps and documents it.";
  m.attr("__version__") = STRIKE_VERSION_STRING;
  m.add_object("InputError", py::reinterpret_steal<py::object>(PyErr_NewExceptionWithDoc(
                                 "strike.InputError", "Bad input: the message names the file, key and value.",
                                 PyExc_ValueError, nullptr)));

  py::class_<ModeBank, std::shared_ptr<ModeBank>>(m, "Bank")
      .def_property_readonly("frequencies_hz",
                             [](const ModeBank& b) {
                               std::vector<double> f(b.modeCount());
                               for (size_t i = 0; i < f.size(); ++i) f[i] = b.frequencyHz(i);
                               return doubles(f);
                             })
      .def_property_readonly("decay_per_s",
                             [](const ModeBank& b) {
                               std::vector<double> d(b.modeCount());
                               for (size_t i = 0; i < d.size(); ++i) d[i] = b.decayPerS(i);
                               return doubles(d);
                             })
      .def_property_readonly("eigenvalues", [](const ModeBank& b) { return doubles(b.eigenvalues); })
      .def_property_readonly("frequency_error_estimate",
                             [](const ModeBank& b) { return doubles(b.frequency_error_estimate); })
      .def_property_readonly("surface_positions_m",
                             [](const ModeBank& b) {
                               return py::array_t<double>(
                                   {static_cast<py::ssize_t>(b.surfaceVertexCount()), py::ssize_t(3)},
                                   b.surface_positions.data());
                             })
      .def_property_readonly("shapes",
                             [](const ModeBank& b) {
                               return py::array_t<float>(
                                   {static_cast<py::ssize_t>(b.modeCount()),
                                    static_cast<py::ssize_t>(b.surfaceVertexCount()), py::ssize_t(3)},
                                   b.shapes.data());
                             })
      .def_property_readonly("max_freq_hz", [](const ModeBank& b) { return b.max_freq_hz; })
      .def("similar",
           [](const ModeBank& b, double scale, const py::dict& material, double max_freq_hz, const std::string& mesh) {
             return std::make_shared<ModeBank>(take(similarBank(b, scale, materialFrom(material), max_freq_hz, mesh)));
           })
      .def_property_readonly("mode_count", &ModeBank::modeCount)
      .def_property_readonly("surface_vertex_count", &ModeBank::surfaceVertexCount)
      .def_property_readonly("mass_kg", [](const ModeBank& b) { return b.mass_kg; })
      .def_property_readonly("volume_m3", [](const ModeBank& b) { return b.volume_m3; })
      .def_property_readonly("element_order", [](const ModeBank& b) { return b.element_order; })
      .def_property_readonly("mesh_source", [](const ModeBank& b) { return b.mesh_source; })
      .def_property_readonly("mesh_hash", [](const ModeBank& b) { return hex64(b.mesh_hash); })
      .def_property_readonly("material", [](const ModeBank& b) { return materialDict(b.material); })
      .def_property_readonly("content_hash",
                             [](const ModeBank& b) {
                               const std::vector<uint8_t> bytes = encodeBank(b);
                               return hex64(fnv1a64(bytes.data(), bytes.size()));
                             })
      .def(
          "save",
          [](const ModeBank& b, const py::object& path_arg) {
            const std::string path = pathOf(path_arg);
            Status status;
            {
              py::gil_scoped_release released;
              status = writeBank(path, b);
            }
            check(status);
          },
          py::arg("path"))
      .def_static(
          "load",
          [](const py::object& path_arg) {
            const std::string path = pathOf(path_arg);
            std::optional<Result<ModeBank>> loaded;
            {
              py::gil_scoped_release released;
              loaded.emplace(readBank(path));
            }
            return std::make_shared<ModeBank>(take(std::move(*loaded)));
          },
          py::arg("path"));

  m.def("material", [](const std::string& name) { return materialDict(take(builtinMaterials().find(name))); });
  m.def("material_names", []() { return builtinMaterials().names(); });
  m.def("can_remesh", &canRemesh);

  m.def("modes",
        [](const std::string& mesh, const py::dict& material, int order, double size_m, double max_freq_hz,
           int max_modes, int64_t max_tets, std::optional<bool> error_estimate, std::optional<double> tolerance,
           bool transfer) {
          return computeModes(mesh, materialFrom(material), order, size_m, max_freq_hz, max_modes, max_tets,
                              error_estimate, tolerance, transfer);
        });

  m.def("hit", [](const ModeBank& bank, std::optional<size_t> vertex, std::optional<std::array<double, 3>> at,
                  std::optional<std::array<double, 3>> impulse, double duration, double rate, double distance,
                  double gain, std::optional<double> contact_time, const std::string& striker, double striker_radius) {
    HitSettings s;
    s.vertex = vertex;
    s.at_m = at;
    s.impulse_n_s = impulse;
    s.duration_s = duration;
    s.sample_rate_hz = rate;
    s.distance_m = distance;
    s.gain = gain;
    s.contact_time_s = contact_time;
    s.striker = striker;
    s.striker_radius_m = striker_radius;
    std::optional<Result<HitResult>> hit;
    {
      py::gil_scoped_release released;
      hit.emplace(renderHit(bank, s));
    }
    HitResult r = take(std::move(*hit));
    py::dict info;
    info["vertex"] = r.vertex;
    info["point_m"] = r.point_m;
    info["impulse_n_s"] = r.impulse_n_s;
    info["contact_time_s"] = r.contact_time_s;
    info["peak"] = r.peak;
    info["clipped_samples"] = r.clipped_samples;
    return py::make_tuple(samples(r.audio), info);
  });

  py::class_<PyRenderResult>(m, "RenderResult")
      .def_property_readonly("audio", [](const PyRenderResult& r) { return samples(r.result.audio); })
      .def_property_readonly("rate", [](const PyRenderResult& r) { return r.result.audio.sample_rate_hz; })
      .def_property_readonly("events", [](const PyRenderResult& r) { return eventsArray(r.result); })
      .def_property_readonly("body_names", [](const PyRenderResult& r) { return r.result.body_names; })
      .def_property_readonly("report", &reportDict)
      .def(
          "save",
          [](const PyRenderResult& r, const std::string& path, const std::string& format) {
            const SampleEncoding encoding = encodingNamed(format);
            Status status;
            {
              py::gil_scoped_release released;
              status = writeAudio(path, r.result.audio, encoding);
            }
            check(status);
          },
          py::arg("path"), py::arg("format"))
      .def(
          "save_events_csv",
          [](const PyRenderResult& r, const std::string& path) { check(writeEventsCsv(path, r.result)); },
          py::arg("path"));

  py::class_<RenderSession, std::shared_ptr<RenderSession>>(m, "Session")
      .def(py::init<uint64_t>(), py::arg("max_bytes") = RenderSession::kDefaultMaxBytes)
      .def_property_readonly("stats",
                             [](const RenderSession& s) {
                               const RenderSession::Stats st = s.stats();
                               py::dict d;
                               d["entries"] = st.entries;
                               d["bytes"] = st.bytes;
                               d["max_bytes"] = st.max_bytes;
                               d["hits"] = st.hits;
                               d["misses"] = st.misses;
                               d["evicted"] = st.evicted;
                               return d;
                             })
      .def("clear", &RenderSession::clear);
  m.def("render_file",
        [](const std::string& path, double rate, double duration, double gain, const std::string& cache_dir,
           int64_t max_tets, int64_t max_events, bool similar, bool transfer, std::shared_ptr<RenderSession> session,
           unsigned solve_threads, const std::string& output, const std::string& hrtf) {
          return renderParsed(loadScene(path), rate, duration, gain, cache_dir, max_tets, max_events, similar, transfer,
                              std::move(session), solve_threads, output, hrtf);
        });
  m.def("render_text", [](const std::string& text, const std::string& path, double rate, double duration, double gain,
                          const std::string& cache_dir, int64_t max_tets, int64_t max_events, bool similar,
                          bool transfer, std::shared_ptr<RenderSession> session, unsigned solve_threads,
                          const std::string& output, const std::string& hrtf) {
    return renderParsed(parseScene(text, path), rate, duration, gain, cache_dir, max_tets, max_events, similar,
                        transfer, std::move(session), solve_threads, output, hrtf);
  });
  m.def("default_cache_dir", &defaultCacheDir);
  m.def("default_max_tets", []() { return static_cast<int64_t>(kDefaultMaxTets); });
  m.def("default_max_events", []() { return static_cast<int64_t>(SimSettings{}.max_events); });
  m.def("write_audio", [](const std::string& path, py::array_t<float, py::array::c_style | py::array::forcecast> audio,
                          double rate, const std::string& format) {
    AudioBuffer buffer;
    buffer.sample_rate_hz = rate;
    buffer.channels = audio.ndim() == 2 ? static_cast<int>(audio.shape(1)) : 1;
    buffer.samples.assign(audio.data(), audio.data() + audio.size());
    check(writeAudio(path, buffer, encodingNamed(format)));
  });
}
