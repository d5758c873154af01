#include "experiments/stages.hpp"

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <fstream>

#include "common/json_fields.hpp"

namespace lanechange::experiments {

namespace fs = std::filesystem;

std::string fingerprint(const std::string& text) {
  std::uint64_t hash = 14695981039346656037ULL;
  for (char c : text) {
    hash ^= static_cast<unsigned char>(c);
    hash *= 1099511628211ULL;
  }
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(hash));
  return hex;
}

StageRunner::StageRunner(std::string out_dir, std::ostream* progress)
    : out_dir_(std::move(out_dir)), progress_(progress) {}

std::string StageRunner::run(const std::string& name, const nlohmann::json& inputs,
                             const std::vector<std::string>& outputs,
                             const std::function<void()>& body) {
  std::string print = fingerprint(inputs.dump());
  const fs::path stamp = fs::path(out_dir_) / "stages" / (name + ".json");
  const auto index = records_.size() + 1;
  if (fs::exists(stamp)) {
    try {
      const auto done = nlohmann::json::parse(std::ifstream(stamp));
      if (done.at("fingerprint") == print) {
        records_.push_back({name, true, done.at("wall_s").get<double>()});
        if (progress_ != nullptr) *progress_ << "== " << index << ". " << name << ": reused\n";
        return print;
      }
    } catch (const nlohmann::json::exception&) {
      // A stamp we cannot read proves nothing: run the stage again.
    }
    fs::remove(stamp);
  }
  if (progress_ != nullptr) *progress_ << "== " << index << ". " << name << "\n";
  // What an earlier run with other inputs left would be refused (or worse,
  // resumed) by the stage: it starts from nothing. A killed run with the same
  // inputs wrote no stamp but its inputs file, and resumes.
  const fs::path started = fs::path(out_dir_) / "stages" / (name + ".inputs.json");
  bool same_inputs = false;
  if (fs::exists(started)) {
    try {
      same_inputs = nlohmann::json::parse(std::ifstream(started)).at("fingerprint") == print;
    } catch (const nlohmann::json::exception&) {
      same_inputs = false;
    }
  }
  if (!same_inputs) {
    for (const auto& output : outputs) fs::remove_all(fs::path(out_dir_) / output);
  }
  fs::create_directories(stamp.parent_path());
  nlohmann::json record = {{"stage", name}, {"fingerprint", print}, {"inputs", inputs}};
  lanechange::detail::write_file_atomically(started.string(), record.dump(2) + "\n");
  const auto start = std::chrono::steady_clock::now();
  body();
  const double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  record["wall_s"] = wall_s;
  lanechange::detail::write_file_atomically(stamp.string(), record.dump(2) + "\n");
  records_.push_back({name, false, wall_s});
  return print;
}

}  // namespace lanechange::experiments
