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

StageRunner::StageRunner(std::string out_dir, std::ostream* progress, run::Team& team)
    : out_dir_(std::move(out_dir)), progress_(team.rank() == 0 ? progress : nullptr), team_(team) {}

bool StageRunner::reuse_or_prepare(const std::string& name, const nlohmann::json& inputs,
                                   const std::string& print,
                                   const std::vector<std::string>& outputs) {
  const fs::path stages = fs::path(out_dir_) / "stages";
  const fs::path stamp = stages / (name + ".json");
  if (fs::exists(stamp)) {
    try {
      if (nlohmann::json::parse(std::ifstream(stamp)).at("fingerprint") == print) return true;
    } catch (const nlohmann::json::exception&) {
      // A stamp we cannot read proves nothing: run the stage again.
    }
    fs::remove(stamp);
  }
  // What an earlier run with other inputs left would be refused (or worse,
  // resumed) by the stage: it starts from nothing. A killed run with the same
  // inputs wrote no stamp but its inputs file, and resumes.
  const fs::path started = stages / (name + ".inputs.json");
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
  fs::create_directories(stages);
  const nlohmann::json record = {{"stage", name}, {"fingerprint", print}, {"inputs", inputs}};
  lanechange::detail::write_file_atomically(started.string(), record.dump(2) + "\n");
  return false;
}

std::string StageRunner::run(const std::string& name, const nlohmann::json& inputs,
                             const std::vector<std::string>& outputs, Ranks ranks,
                             const std::function<void()>& body) {
  std::string print = fingerprint(inputs.dump());
  const auto index = records_.size() + 1;
  const fs::path stamp = fs::path(out_dir_) / "stages" / (name + ".json");
  const bool reuse = run::decide_on_rank_zero(team_, "--out", [&] {
                       return reuse_or_prepare(name, inputs, print, outputs) ? 1 : 0;
                     }) == 1;
  if (reuse) {
    double wall_s = 0.0;
    if (team_.rank() == 0) {
      wall_s = nlohmann::json::parse(std::ifstream(stamp)).at("wall_s").get<double>();
    }
    records_.push_back({name, true, wall_s});
    if (progress_ != nullptr) *progress_ << "== " << index << ". " << name << ": reused\n";
    return print;
  }
  if (progress_ != nullptr) *progress_ << "== " << index << ". " << name << "\n";
  const auto start = std::chrono::steady_clock::now();
  if (ranks == Ranks::All) {
    body();
  } else {
    // The other ranks wait in the broadcast, and learn of a failure there.
    (void)run::decide_on_rank_zero(team_, name, [&] {
      body();
      return 0;
    });
  }
  team_.barrier();
  const double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (team_.rank() == 0) {
    nlohmann::json record = {
        {"stage", name}, {"fingerprint", print}, {"inputs", inputs}, {"wall_s", wall_s}};
    lanechange::detail::write_file_atomically(stamp.string(), record.dump(2) + "\n");
  }
  records_.push_back({name, false, wall_s});
  return print;
}

}  // namespace lanechange::experiments
