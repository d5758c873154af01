#pragma once
// Field-by-field JSON reading and writing for plain structs. A struct takes
// part by offering, findable by ADL,
//   template <class Visitor, class Self> void visit_fields(Visitor& v, Self& s)
// that calls v("name", s.member) for each member. Reading checks the type and
// finiteness of every number and rejects unknown keys, naming the JSON path.
#include <cmath>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <span>
#include <string>
#include <string_view>
#include <utility>

#include "lanechange/config.hpp"
#include "lanechange/error.hpp"

namespace lanechange::detail {

using nlohmann::json;

template <class Enum>
struct EnumName {
  Enum value;
  const char* name;
};

struct FieldReader;
struct FieldWriter;

template <class T>
concept FieldStruct = requires(FieldWriter& w, const T& t) {
  visit_fields(w, t);
};

template <class T>
concept NamedEnum = std::is_enum_v<T> && requires(T t) {
  enum_names(t);
};

inline std::string join_path(const std::string& path, const std::string& key) {
  return path.empty() ? key : path + "." + key;
}

inline void read_value(const json& j, const std::string& path, double& out) {
  if (!j.is_number()) throw InputError(path, "must be a number");
  out = j.get<double>();
  if (!std::isfinite(out)) throw InputError(path, "must be finite");
}

// null stands for "none" (a cap that is not asked for).
inline void read_value(const json& j, const std::string& path, std::optional<double>& out) {
  if (j.is_null()) {
    out.reset();
    return;
  }
  double value = 0.0;
  read_value(j, path, value);
  out = value;
}

inline void read_value(const json& j, const std::string& path, int& out) {
  if (!j.is_number_integer()) throw InputError(path, "must be an integer");
  out = j.get<int>();
}

inline void read_value(const json& j, const std::string& path, bool& out) {
  if (!j.is_boolean()) throw InputError(path, "must be true or false");
  out = j.get<bool>();
}

inline void read_value(const json& j, const std::string& path, std::string& out) {
  if (!j.is_string()) throw InputError(path, "must be a string");
  out = j.get<std::string>();
}

inline void read_value(const json& j, const std::string& path, Interval& out) {
  if (!j.is_array() || j.size() != 2) throw InputError(path, "must be an array [lo, hi]");
  read_value(j[0], path + "[0]", out.lo);
  read_value(j[1], path + "[1]", out.hi);
  if (out.lo > out.hi) throw InputError(path, "lower bound exceeds upper bound");
}

template <NamedEnum Enum>
void read_value(const json& j, const std::string& path, Enum& out) {
  std::string text;
  read_value(j, path, text);
  std::string allowed;
  for (const auto& entry : enum_names(out)) {
    if (text == entry.name) {
      out = entry.value;
      return;
    }
    allowed += allowed.empty() ? entry.name : std::string(", ") + entry.name;
  }
  throw InputError(path, "unknown value \"" + text + "\" (expected one of: " + allowed + ")");
}

template <NamedEnum Enum>
const char* enum_to_string(Enum value) {
  for (const auto& entry : enum_names(value)) {
    if (entry.value == value) return entry.name;
  }
  return "?";
}

template <FieldStruct T>
void read_value(const json& j, const std::string& path, T& out);

struct FieldReader {
  const json& object;
  std::string path;
  std::set<std::string> known;

  template <class T>
  void operator()(const char* name, T& value) {
    known.insert(name);
    if (auto it = object.find(name); it != object.end())
      read_value(*it, join_path(path, name), value);
  }

  void reject_unknown_keys() const {
    for (const auto& item : object.items()) {
      if (!known.contains(item.key()))
        throw InputError(join_path(path, item.key()), "unknown field");
    }
  }
};

template <FieldStruct T>
void read_value(const json& j, const std::string& path, T& out) {
  if (!j.is_object()) throw InputError(path, "must be an object");
  FieldReader reader{j, path, {}};
  visit_fields(reader, out);
  reader.reject_unknown_keys();
}

inline json write_value(double v) { return v; }
inline json write_value(const std::optional<double>& v) { return v ? json(*v) : json(nullptr); }
inline json write_value(int v) { return v; }
inline json write_value(bool v) { return v; }
inline json write_value(const std::string& v) { return v; }
inline json write_value(const Interval& v) { return json::array({v.lo, v.hi}); }
template <NamedEnum Enum>
json write_value(Enum v) {
  return enum_to_string(v);
}
template <FieldStruct T>
json write_value(const T& v);

struct FieldWriter {
  json& out;
  template <class T>
  void operator()(const char* name, const T& value) {
    out[name] = write_value(value);
  }
};

template <FieldStruct T>
json write_value(const T& v) {
  json out = json::object();
  FieldWriter writer{out};
  visit_fields(writer, v);
  return out;
}

/// Parses text as JSON, turning a syntax error into an InputError.
json parse_json_text(const std::string& text, const std::string& what);
/// Reads a whole file and parses it; a missing file is an InputError too.
json read_json_file(const std::string& path);
/// A file written atomically, piece by piece: the text goes to a temporary
/// file in the same directory (PATH.tmp.PID); commit() fsyncs it, renames it
/// to PATH and fsyncs the directory. A crash never leaves a half-written file
/// where a good one stood; destroyed uncommitted, it removes the temporary.
class AtomicFile {
 public:
  explicit AtomicFile(const std::string& path);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;
  void write(std::string_view text);
  void commit();

 private:
  std::string path_;
  std::string temporary_;
  int fd_ = -1;
};

/// The whole text through an AtomicFile.
void write_file_atomically(const std::string& path, const std::string& text);

}  // namespace lanechange::detail
