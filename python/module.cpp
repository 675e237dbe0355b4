// ccdbench's Python module (_ccdbench, wrapped by ccdbench/__init__.py): the C++ API (api/ccdbench/ccdbench.hpp)
// with numpy arrays in and out. The GIL is released around every call that works (the oracle uses every core); a
// Python method is called with it held, from one thread at a time, on a read-only copy of its pairs' rows.

#include <ccdbench/ccdbench.hpp>

#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <cstring>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace py = pybind11;

namespace {

ccdbench::PairKind pair_kind(const std::string& kind) {
  if (kind == "vertex-face" || kind == "vf") return ccdbench::PairKind::vertex_face;
  if (kind == "edge-edge" || kind == "ee") return ccdbench::PairKind::edge_edge;
  throw std::invalid_argument("kind '" + kind + "' is neither 'vertex-face' ('vf') nor 'edge-edge' ('ee')");
}

const char* kind_name(ccdbench::PairKind kind) { return kind == ccdbench::PairKind::vertex_face ? "vertex-face" : "edge-edge"; }

/// A read-only float64 array holding a copy of `count` pairs' rows, shape (count, 8, 3).
py::array_t<double> rows_array(const ccdbench::Rows* rows, std::size_t count) {
  py::array_t<double> array({static_cast<py::ssize_t>(count), py::ssize_t{8}, py::ssize_t{3}});
  if (count > 0) std::memcpy(array.mutable_data(), rows, count * sizeof(ccdbench::Rows));
  py::detail::array_proxy(array.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return array;
}

/// Queries given as an (N, 8, 3) float64 array (converted when it is another numeric array).
py::array_t<double, py::array::c_style | py::array::forcecast> query_array(const py::handle& queries) {
  auto array = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(queries);
  if (!array) throw std::invalid_argument("queries must be a numeric array of shape (N, 8, 3)");
  if (array.ndim() != 3 || array.shape(1) != 8 || array.shape(2) != 3) {
    std::string shape;
    for (py::ssize_t d = 0; d < array.ndim(); ++d) {
      if (d > 0) shape += ", ";
      shape += std::to_string(array.shape(d));
    }
    throw std::invalid_argument("queries must have shape (N, 8, 3), not (" + shape + ")");
  }
  return array;
}

py::dict answers_dict(const std::vector<ccdbench::ExactAnswer>& answers) {
  const auto n = static_cast<py::ssize_t>(answers.size());
  py::array_t<bool> collides(n), by_filter(n);
  py::array_t<double> lower(n), upper(n);
  for (py::ssize_t i = 0; i < n; ++i) {
    const ccdbench::ExactAnswer& a = answers[static_cast<std::size_t>(i)];
    collides.mutable_at(i) = a.collides;
    by_filter.mutable_at(i) = a.by_filter;
    lower.mutable_at(i) = a.toi_lower.value_or(std::nan(""));
    upper.mutable_at(i) = a.toi_upper.value_or(std::nan(""));
  }
  py::dict result;
  result["collides"] = collides;
  result["toi_lower"] = lower;
  result["toi_upper"] = upper;
  result["by_filter"] = by_filter;
  return result;
}

/// A Python method's answer to one batch, read strictly: hits, or (hits, tois), each of shape (N,); anything else
/// throws, which makes the batch's pairs errors (asked again one at a time to place the error).
void read_python_answer(const py::object& returned, std::size_t count, ccdbench::MethodAnswers& answers) {
  if (returned.is_none()) throw std::runtime_error("it returned None");
  py::object hits = returned, tois = py::none();
  if (py::isinstance<py::tuple>(returned)) {
    const py::tuple pair = returned.cast<py::tuple>();
    if (pair.size() != 2) throw std::runtime_error("it returned a tuple of " + std::to_string(pair.size()) + ", not (hits, tois)");
    hits = pair[0];
    tois = pair[1];
  }
  // Only booleans, integers and IEEE doubles (or narrower floats) are read, each exactly as a double: strings,
  // complex numbers, masked arrays and long doubles are errors, not answers after a conversion that changes them.
  auto column = [&](const py::object& value, const char* what) {
    const py::module_ numpy = py::module_::import("numpy");
    if (py::isinstance(value, numpy.attr("ma").attr("MaskedArray"))) throw std::runtime_error(std::string("its ") + what + " are a masked array");
    const py::array given = numpy.attr("asarray")(value);
    const char kind = given.dtype().kind();
    const bool allowed = kind == 'b' || kind == 'i' || kind == 'u' || (kind == 'f' && given.dtype().itemsize() <= 8);
    if (!allowed || given.ndim() != 1 || static_cast<std::size_t>(given.shape(0)) != count) {
      throw std::runtime_error(std::string("its ") + what + " are not an array of shape (" + std::to_string(count) +
                               ",) of booleans, integers or doubles");
    }
    return py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(given);
  };
  const auto hit_values = column(hits, "hits");
  answers.hits.resize(count);
  answers.errors.assign(count, {});
  for (std::size_t i = 0; i < count; ++i) {
    const double h = hit_values.at(static_cast<py::ssize_t>(i));
    if (h == 0 || h == 1) {
      answers.hits[i] = static_cast<std::uint8_t>(h);
    } else {
      answers.errors[i] = "hit " + std::to_string(h) + " is neither 0 nor 1";
    }
  }
  if (!tois.is_none()) {
    const auto toi_values = column(tois, "TOIs");
    answers.tois.assign(toi_values.data(), toi_values.data() + count);
  }
}

/// A Python callable held by C++ code that may drop it without the GIL (a cell ends inside a call that released
/// it): its reference is given back with the GIL held.
struct PythonCallable {
  explicit PythonCallable(py::function f) : function(std::move(f)) {}
  PythonCallable(const PythonCallable&) = delete;
  PythonCallable& operator=(const PythonCallable&) = delete;
  ~PythonCallable() {
    py::gil_scoped_acquire gil;
    function = py::function();
  }
  py::function function;
};

/// The exception that ended a call (KeyboardInterrupt, SystemExit: not an Exception), raised again where the call
/// returns to Python. Read and written with the GIL held.
std::optional<py::error_already_set>& interruption() {
  static std::optional<py::error_already_set> pending;
  return pending;
}

/// Re-raises the interruption a Python method made, at the call that ran it.
[[noreturn]] void raise_interruption(const ccdbench::MethodInterrupted& interrupted) {
  if (interruption()) {
    py::error_already_set error = std::move(*interruption());
    interruption().reset();
    throw error;
  }
  throw std::runtime_error(interrupted.what());
}

/// Runs `call` with the GIL released; a Python method's interruption is raised again here.
template <class Call>
auto without_gil(Call call) {
  try {
    py::gil_scoped_release released;
    return call();
  } catch (const ccdbench::MethodInterrupted& interrupted) {
    raise_interruption(interrupted);
  }
}

/// Registers a Python callable f(kind, q, delta) as callable:NAME.
void register_python_method(const std::string& name, py::function f, std::size_t batch) {
  auto held = std::make_shared<PythonCallable>(std::move(f));
  ccdbench::register_method(
      name,
      [held](const ccdbench::MethodBatch& asked, ccdbench::MethodAnswers& answers) {
        py::gil_scoped_acquire gil;
        try {
          py::object returned = held->function(kind_name(asked.kind), rows_array(asked.rows, asked.count), asked.thickness);
          read_python_answer(returned, asked.count, answers);
        } catch (py::error_already_set& error) {
          if (!error.matches(PyExc_Exception)) {
            // KeyboardInterrupt, SystemExit, GeneratorExit: the user's, never the batch's error. The call ends here.
            const std::string message = error.what();
            interruption() = std::move(error);
            throw ccdbench::MethodInterrupted(message.substr(0, message.find('\n')));
          }
          // The Python exception, as its type and message, is the batch's error.
          const std::string message = error.what();
          throw std::runtime_error(message.substr(0, message.find('\n')));
        }
      },
      batch);
}

}  // namespace

namespace {

/// The version and the exact oracle on arrays.
void bind_oracle(py::module_& m) {
  m.doc() = "ccdbench's C++ API (ccdbench.hpp) for Python; use the ccdbench package, which wraps it";

  m.def("version", [] {
    const ccdbench::Version v = ccdbench::version();
    return std::to_string(v.major) + "." + std::to_string(v.minor) + "." + std::to_string(v.patch);
  });

  m.def(
      "oracle",
      [](const std::string& kind, const py::handle& queries, double delta, bool toi) {
        const auto array = query_array(queries);
        const auto* rows = reinterpret_cast<const ccdbench::Rows*>(array.data());
        const auto count = static_cast<std::size_t>(array.shape(0));
        const ccdbench::PairKind k = pair_kind(kind);
        return answers_dict(without_gil([&] { return ccdbench::exact_oracle(k, rows, count, delta, toi); }));
      },
      py::arg("kind"), py::arg("queries"), py::arg("delta") = 0.0, py::arg("toi") = true);
}

/// Query files: read, written, decided on their rationals.
void bind_query_files(py::module_& m) {
  py::class_<ccdbench::QueryFile>(m, "QueryFile")
      .def_readonly("path", &ccdbench::QueryFile::path)
      .def_property_readonly("kind", [](const ccdbench::QueryFile& f) { return std::string(kind_name(f.kind)); })
      .def("__len__", [](const ccdbench::QueryFile& f) { return f.exact.size(); })
      .def_property_readonly("queries", [](const ccdbench::QueryFile& f) { return rows_array(f.rounded.data(), f.rounded.size()); })
      .def_property_readonly("rationals", [](const ccdbench::QueryFile& f) { return f.exact; })
      .def_property_readonly("labels",
                             [](const ccdbench::QueryFile& f) {
                               py::array_t<std::int8_t> labels(static_cast<py::ssize_t>(f.truth.size()));
                               for (std::size_t q = 0; q < f.truth.size(); ++q)
                                 labels.mutable_at(static_cast<py::ssize_t>(q)) = static_cast<std::int8_t>(f.truth[q]);
                               return labels;
                             })
      .def_property_readonly("exactly_double", [](const ccdbench::QueryFile& f) {
        py::array_t<bool> exact(static_cast<py::ssize_t>(f.exactly_double.size()));
        for (std::size_t q = 0; q < f.exactly_double.size(); ++q) exact.mutable_at(static_cast<py::ssize_t>(q)) = f.exactly_double[q];
        return exact;
      });

  m.def("read_query_file", [](const std::string& path) {
    py::gil_scoped_release released;
    return ccdbench::read_query_file(path);
  });
  m.def("write_query_file", [](const std::string& path, const std::vector<ccdbench::RationalRows>& rationals, const std::vector<int>& labels) {
    ccdbench::QueryFile file;
    file.exact = rationals;
    file.truth = labels;
    py::gil_scoped_release released;
    ccdbench::write_query_file(path, file);
  });
  m.def(
      "oracle_file",
      [](const ccdbench::QueryFile& file, const std::string& delta, bool toi) {
        std::vector<ccdbench::ExactAnswer> answers;
        {
          py::gil_scoped_release released;
          answers = ccdbench::exact_oracle(file, delta, toi);
        }
        return answers_dict(answers);
      },
      py::arg("file"), py::arg("delta") = "0", py::arg("toi") = true);
}

/// Python methods registered for scoring, and methods scored on query files.
void bind_methods(py::module_& m) {
  m.def("register_method", &register_python_method, py::arg("name"), py::arg("f"), py::arg("batch") = 0);
  m.def("unregister_method", [](const std::string& name) {
    py::gil_scoped_release released;  // a run on another thread may hold the registry's lock while it waits for the GIL
    ccdbench::unregister_method(name);
  });

  m.def("score_queries", [](const std::vector<std::string>& paths, const std::vector<std::string>& methods, double delta, bool toi, int repeats) {
    const std::vector<ccdbench::Score> scores = without_gil([&] { return ccdbench::score_queries(paths, methods, delta, toi, repeats); });
    py::list rows;
    auto optional = [](const auto& value) -> py::object { return value ? py::cast(*value) : py::none(); };
    for (const ccdbench::Score& s : scores) {
      py::dict row;
      row["method"] = s.method;
      row["file"] = s.file;
      row["queries"] = s.queries;
      row["reported"] = s.reported;
      row["errors"] = s.errors;
      row["unlabelled"] = s.unlabelled;
      row["positives"] = optional(s.positives);
      row["false_negatives"] = optional(s.false_negatives);
      row["false_positives"] = optional(s.false_positives);
      row["ns_per_query"] = s.ns_per_query;
      row["toi_checked"] = s.toi_checked;
      row["toi_late"] = s.toi_late;
      row["toi_error_max"] = optional(s.toi_error_max);
      row["toi_error_median"] = optional(s.toi_error_median);
      row["toi_error_p99"] = optional(s.toi_error_p99);
      row["changed_between_passes"] = s.changed_between_passes;
      rows.append(row);
    }
    return rows;
  });
}

/// Scenes: built-in, generated, loaded; their frames as arrays.
void bind_scenes(py::module_& m) {
  py::class_<ccdbench::Scene>(m, "Scene")
      .def_property_readonly("label", &ccdbench::Scene::label)
      .def_property_readonly("file", &ccdbench::Scene::file)
      .def_property_readonly("num_vertices", &ccdbench::Scene::num_vertices)
      .def_property_readonly("num_frames", &ccdbench::Scene::num_frames)
      .def_property_readonly("thickness", &ccdbench::Scene::thickness)
      .def_property_readonly("faces",
                             [](const ccdbench::Scene& s) {
                               const auto& faces = s.faces();
                               py::array_t<std::uint32_t> array({static_cast<py::ssize_t>(faces.size()), py::ssize_t{3}});
                               if (!faces.empty()) std::memcpy(array.mutable_data(), faces.data(), faces.size() * sizeof(faces[0]));
                               return array;
                             })
      .def("frame", [](const ccdbench::Scene& s, std::size_t k) {
        const std::vector<ccdbench::Point> points = s.frame(k);
        py::array_t<double> array({static_cast<py::ssize_t>(points.size()), py::ssize_t{3}});
        if (!points.empty()) std::memcpy(array.mutable_data(), points.data(), points.size() * sizeof(points[0]));
        return array;
      });

  m.def("builtin_scenes", [] {
    py::list scenes;
    for (const ccdbench::SceneInfo& info : ccdbench::builtin_scenes()) {
      py::dict parameters;
      for (const auto& [name, value] : info.parameters) parameters[py::str(name)] = value;
      scenes.append(py::dict(py::arg("name") = info.name, py::arg("description") = info.description, py::arg("parameters") = parameters));
    }
    return scenes;
  });
  m.def("generate_scene", [](const std::string& name, const std::map<std::string, double>& parameters) {
    py::gil_scoped_release released;
    return ccdbench::generate_scene(name, parameters);
  });
  m.def("load_scene", [](const std::string& path) {
    py::gil_scoped_release released;
    return ccdbench::load_scene(path);
  });
}

/// Strategies, runs of cells verified against the exact truth, and the gate.
void bind_runs(py::module_& m) {
  m.def("strategy_names", &ccdbench::strategy_names);
  m.def("validate_strategy", &ccdbench::validate_strategy);

  m.def("run",
        [](const std::vector<ccdbench::Scene>& scenes, const std::vector<std::string>& strategies,
           const std::vector<std::optional<double>>& thicknesses, bool verify, bool toi, int repeats, std::size_t max_steps, const std::string& out) {
          ccdbench::RunRequest request;
          request.scenes = scenes;
          request.strategies = strategies;
          request.thicknesses = thicknesses;
          request.verify = verify;
          request.toi = toi;
          request.repeats = repeats;
          request.max_steps = max_steps;
          request.out = out;
          const std::vector<ccdbench::CellSummary> cells = without_gil([&] { return ccdbench::run(request); });
          std::vector<std::string> records;
          for (const ccdbench::CellSummary& cell : cells) records.push_back(cell.json);
          return records;
        });

  m.def("write_baseline", [](const std::string& baseline, const std::vector<std::string>& records, const std::string& margin) {
    std::vector<ccdbench::CellSummary> cells(records.size());
    for (std::size_t i = 0; i < records.size(); ++i) cells[i].json = records[i];
    py::gil_scoped_release released;
    return ccdbench::write_baseline(baseline, cells, margin);
  });

  m.def("check", [](const std::string& baseline, const std::vector<std::string>& records) {
    std::vector<ccdbench::CellSummary> cells(records.size());
    for (std::size_t i = 0; i < records.size(); ++i) cells[i].json = records[i];
    ccdbench::GateResult result;
    {
      py::gil_scoped_release released;
      result = ccdbench::check(baseline, cells);
    }
    return py::make_tuple(result.passed, result.lines);
  });
}
}  // namespace

PYBIND11_MODULE(_ccdbench, m) {
  bind_oracle(m);
  bind_query_files(m);
  bind_methods(m);
  bind_scenes(m);
  bind_runs(m);
}
