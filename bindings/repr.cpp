// Readable __repr__ for every bound class that has none of its own: `Type(field=value unit, ...)`
// built from the class's properties, with the unit taken from the property's docstring ("... [N]")
// or from the table below. Installed once, after all classes are bound (module.cpp). Scalars print
// as format_number (shortest round-trip text, as the hand-written reprs do); arrays print 4
// significant digits (a summary).
#include <algorithm>
#include <map>
#include <regex>
#include <string>
#include <vector>

#include <pybind11/eval.h>

#include "bindings.hpp"

namespace py = pybind11;

namespace ernest::bindings {
namespace {

constexpr std::size_t kMaxFields = 12;  // more are elided with ", ..."

enum class Kind { Scalar, Array, Nested };

struct Field {
  std::string name;
  std::string unit;
  Kind kind;
};

// Units of fields whose docstrings do not state them.
const std::map<std::string, std::map<std::string, std::string>>& unit_table() {
  static const std::map<std::string, std::map<std::string, std::string>> t = {
      {"RoverState",
       {{"time", "s"}, {"roll", "rad"}, {"pitch", "rad"}, {"yaw", "rad"}, {"gimbal_yaw", "rad"},
        {"gimbal_roll", "rad"}, {"wheel_speed", "rad/s"}, {"wheel_torque", "N m"},
        {"wheel_load", "N"}, {"sinkage", "m"}, {"roll_torque", "N m"}, {"yaw_torque", "N m"},
        {"energy", "J"}}},
      {"TransitionMetrics",
       {{"duration", "s"}, {"heading_change", "rad"}, {"heading_deviation", "rad"},
        {"position_deviation", "m"}, {"distance", "m"}, {"energy", "J"},
        {"energy_wheels", "J"}, {"energy_articulation", "J"}}},
      {"TransitionResult", {{"t1", "s"}}},
      {"TransitionProblem", {{"t1", "s"}}},
      {"MassFitResult", {{"rmse", "N"}, {"residual_sigma", "N"}}},
      {"Snapshot", {{"time", "s"}}},
      {"Pose2", {{"x", "m"}, {"y", "m"}, {"heading", "rad"}}},
      {"StabilityMargins", {{"ssm", "m"}, {"nesm", "m"}, {"ssm_cps", "m"}, {"nesm_cps", "m"}}},
  };
  return t;
}

// The fields shown for classes with many: the main ones, in this order.
const std::map<std::string, std::vector<std::string>>& main_fields() {
  static const std::map<std::string, std::vector<std::string>> t = {
      {"RoverState",
       {"time", "position", "roll", "pitch", "yaw", "gimbal_yaw", "gimbal_roll", "clutch",
        "wheel_load", "sinkage", "slip", "energy"}},
      {"TransitionMetrics",
       {"duration", "heading_change", "heading_deviation", "position_deviation", "distance",
        "energy", "cost_of_transport", "max_acceleration"}},
      {"TransitionResult",
       {"requested", "strategy", "fell_back", "t1", "duration", "phase_shift", "cost",
        "max_violation", "seconds"}},
      {"MassFitResult",
       {"model", "r_squared", "rmse", "residual_sigma", "rank", "converged", "status"}},
  };
  return t;
}

// The unit in a docstring: the last bracket holding letters and no comma ("eq 30 [N]" -> "N").
std::string unit_from_doc(const std::string& doc) {
  static const std::regex bracket(R"(\[([^\[\],]*[A-Za-z][^\[\],]*)\])");
  std::string unit;
  for (auto it = std::sregex_iterator(doc.begin(), doc.end(), bracket); it != std::sregex_iterator();
       ++it)
    unit = (*it)[1].str();
  return unit;
}

// The return annotation of a pybind11 getter ("(self: X) -> float" -> "float").
std::string return_type(const py::handle& prop) {
  const py::object fget = prop.attr("fget");
  if (fget.is_none() || !py::hasattr(fget, "__doc__") || fget.attr("__doc__").is_none()) return "";
  std::string doc = fget.attr("__doc__").cast<std::string>();
  doc = doc.substr(0, doc.find('\n'));
  const auto arrow = doc.rfind("-> ");
  return arrow == std::string::npos ? "" : doc.substr(arrow + 3);
}

bool is_bound_class(const py::handle& obj) {
  return py::isinstance<py::type>(obj) && py::hasattr(obj, "__module__") &&
         obj.attr("__module__").cast<std::string>().rfind("ernest_cpp._core", 0) == 0;
}

// A class of plain data: properties only, besides validate() and static constructors. Objects
// (simulators, planners, results with methods) show only their scalar fields: their other
// getters may copy large state.
bool is_plain(const py::handle& cls) {
  const py::dict d = cls.attr("__dict__");
  for (auto item : d) {
    const std::string name = py::str(item.first);
    if (name.rfind("_", 0) == 0 || name == "validate") continue;
    if (py::isinstance(item.second, py::module_::import("builtins").attr("property"))) continue;
    if (py::isinstance(item.second, py::module_::import("builtins").attr("staticmethod"))) continue;
    return false;
  }
  return true;
}

bool has_own_repr(const py::handle& cls) {
  for (auto base : cls.attr("__mro__")) {
    if (!is_bound_class(base)) break;  // pybind11_object and object print "<... at 0x...>"
    if (py::dict(base.attr("__dict__")).contains("__repr__")) return true;
  }
  return false;
}

// How a getter's value is shown, from its signature; false when it is not shown.
bool classify(const py::module_& core, const std::string& type, bool plain, Kind& kind) {
  if (type == "float" || type == "int" || type == "bool" || type == "str") {
    kind = Kind::Scalar;
    return true;
  }
  const std::string prefix = "ernest_cpp._core.";
  if (type.rfind(prefix, 0) == 0) {
    const std::string path = type.substr(prefix.size());  // "dynamics.ClutchState"
    const auto dot = path.find('.');
    if (dot == std::string::npos || path.find_first_of(" |[", dot) != std::string::npos) return false;
    const py::object module = core.attr(path.substr(0, dot).c_str());
    if (!py::hasattr(module, path.substr(dot + 1).c_str())) return false;
    const py::object cls = module.attr(path.substr(dot + 1).c_str());
    if (py::hasattr(cls, "__members__")) {  // an enum
      kind = Kind::Scalar;
      return true;
    }
    kind = Kind::Nested;  // shown when small: plain data, or a class with its own short repr
    return plain && (is_plain(cls) || has_own_repr(cls));
  }
  const bool numeric = type.find("NDArray") != std::string::npos ||
                       type.find("list[float]") != std::string::npos ||
                       type.find("list[int]") != std::string::npos ||
                       type.find("list[bool]") != std::string::npos ||
                       type.rfind("tuple[float", 0) == 0;
  kind = Kind::Array;
  return numeric && plain;
}

std::vector<Field> fields_of(const py::module_& core, const py::handle& cls,
                             const std::string& name) {
  const bool plain = is_plain(cls);
  const auto units = unit_table().count(name) ? unit_table().at(name)
                                               : std::map<std::string, std::string>{};
  std::vector<Field> all;
  const py::object property = py::module_::import("builtins").attr("property");
  for (auto item : py::dict(cls.attr("__dict__"))) {
    const std::string field = py::str(item.first);
    if (field.rfind("_", 0) == 0 || !py::isinstance(item.second, property)) continue;
    Kind kind;
    if (!classify(core, return_type(item.second), plain, kind)) continue;
    std::string unit;
    if (!item.second.attr("__doc__").is_none())
      unit = unit_from_doc(item.second.attr("__doc__").cast<std::string>());
    if (unit.empty() && units.count(field)) unit = units.at(field);
    if (unit == "-") unit.clear();
    all.push_back({field, unit, kind});
  }
  if (!main_fields().count(name)) return all;
  std::vector<Field> chosen;
  for (const auto& want : main_fields().at(name))
    for (const auto& f : all)
      if (f.name == want) chosen.push_back(f);
  return chosen;
}

std::string format_value(const py::object& value, Kind kind) {
  if (kind == Kind::Nested) return py::repr(value);
  if (py::isinstance<py::float_>(value)) return format_number(value.cast<double>());
  if (py::isinstance<py::str>(value) || py::isinstance<py::bool_>(value) ||
      py::isinstance<py::int_>(value))
    return py::repr(value);
  if (kind == Kind::Scalar) return py::str(value);  // an enum: Strategy.Bezier
  const py::module_ np = py::module_::import("numpy");
  const py::object a = np.attr("asarray")(value);
  if (a.attr("size").cast<std::size_t>() > 12) {  // large: the shape only
    std::string shape = py::str(a.attr("shape"));
    return "<array " + shape + ">";
  }
  // Never freed: a static py::object would be released after the interpreter has finalised.
  static const py::object* formatter =
      new py::object(py::eval("{'float_kind': lambda x: format(x, '.4g')}"));
  std::string s = np.attr("array2string")(a, py::arg("separator") = ", ",
                                          py::arg("formatter") = *formatter,
                                          py::arg("max_line_width") = 100000)
                      .cast<std::string>();
  s.erase(std::remove(s.begin(), s.end(), '\n'), s.end());
  return s;
}

void install(const py::handle& cls, const std::string& name, const std::vector<Field>& fields) {
  cls.attr("__repr__") = py::cpp_function(
      [name, fields](py::handle self) {
        if (fields.empty()) return "<" + name + ">";
        std::string out = name + "(";
        std::size_t shown = 0;
        for (const auto& f : fields) {
          if (shown == kMaxFields) {
            out += ", ...";
            break;
          }
          std::string text;
          try {
            text = format_value(self.attr(f.name.c_str()), f.kind);
          } catch (const py::error_already_set&) {
            continue;  // a getter that refuses in this state (e.g. before reset): left out
          }
          out += (shown++ ? ", " : "") + f.name + "=" + text + (f.unit.empty() ? "" : " " + f.unit);
        }
        return out + ")";
      },
      py::name("__repr__"), py::is_method(cls));
}


}  // namespace

std::string format_number(double x) {
  // Python's float repr is the shortest text that reads back to x (and switches to an exponent
  // below 1e-4 and from 1e16, where to_chars's shortest form would pick 1e+05 for 100000).
  std::string s = py::repr(py::float_(x)).cast<std::string>();
  if (s.size() > 2 && s.compare(s.size() - 2, 2, ".0") == 0) s.resize(s.size() - 2);
  return s;
}

void add_reprs(py::module_& core) {
  const py::object base_exception = py::module_::import("builtins").attr("BaseException");
  std::vector<py::object> todo;  // found first: a base given a repr here must not hide a subclass
  for (auto item : py::dict(core.attr("__dict__"))) {
    if (!py::isinstance<py::module_>(item.second)) continue;
    for (auto member : py::dict(item.second.attr("__dict__"))) {
      const py::handle cls = member.second;
      if (!is_bound_class(cls) || py::hasattr(cls, "__members__")) continue;  // enums have one
      if (PyObject_IsSubclass(cls.ptr(), base_exception.ptr()) == 1) continue;
      if (!has_own_repr(cls)) todo.push_back(py::reinterpret_borrow<py::object>(cls));
    }
  }
  std::vector<std::vector<Field>> fields;  // all before any install (has_own_repr above)
  for (const auto& cls : todo)
    fields.push_back(fields_of(core, cls, cls.attr("__name__").cast<std::string>()));
  for (std::size_t i = 0; i < todo.size(); ++i)
    install(todo[i], todo[i].attr("__name__").cast<std::string>(), fields[i]);
}

}  // namespace ernest::bindings
