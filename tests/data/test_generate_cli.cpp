#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <thread>

#include "data_helpers.hpp"

namespace lanechange {
namespace {

namespace fs = std::filesystem;
using testing::run_cli;
using testing::small_run;
using testing::TempDir;

int count_files(const fs::path& dir, const std::string& prefix) {
  int n = 0;
  if (!fs::exists(dir)) return 0;
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    // A temporary file is a shard being written, not a finished one.
    n += name.rfind(prefix, 0) == 0 && name.find(".tmp.") == std::string::npos ? 1 : 0;
  }
  return n;
}

// Starts the CLI as a child process (output discarded); returns its pid.
pid_t spawn_cli(const std::vector<std::string>& args) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    std::vector<char*> argv;
    argv.push_back(const_cast<char*>(LANECHANGE_CLI));
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    if (std::freopen("/dev/null", "w", stderr) == nullptr) ::_exit(127);
    ::execv(LANECHANGE_CLI, argv.data());
    ::_exit(127);
  }
  return pid;
}

std::vector<std::string> long_run(const fs::path& out, const std::string& jobs) {
  return {"generate",     "--count", "60",     "--seed", "4",     "--steps",   "8",
          "--shard-size", "2",       "--jobs", jobs,     "--out", out.string()};
}

std::string joined(const std::vector<std::string>& args) {
  std::string command;
  for (const auto& a : args) command += a + " ";
  return command;
}

TEST(GenerateCli, KilledRunResumesToTheUninterruptedResult) {
  TempDir dir;
  const fs::path killed = dir.path() / "killed";
  const fs::path whole = dir.path() / "whole";
  const auto args = long_run(killed, "1");
  const pid_t child = spawn_cli(args);
  ASSERT_GT(child, 0);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (count_files(killed, "scenarios-") < 3 && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  ASSERT_EQ(::kill(child, SIGKILL), 0);
  int status = 0;
  ::waitpid(child, &status, 0);
  ASSERT_TRUE(WIFSIGNALED(status)) << "the run ended before it could be killed";
  const int finished = count_files(killed, "scenarios-");
  ASSERT_GE(finished, 3);
  ASSERT_LT(finished, 30) << "the run was nearly done when killed; make it longer";
  EXPECT_EQ(testing::read_manifest(killed)["status"], "incomplete");
  EXPECT_EQ(run_cli("dataset-info --data " + killed.string()).exit_code, 2);

  const auto resumed = run_cli(joined(args));
  ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
  EXPECT_NE(resumed.output.find(std::to_string(finished) + " finished before"), std::string::npos)
      << resumed.output;

  const auto uninterrupted = run_cli(joined(long_run(whole, "2")));
  ASSERT_EQ(uninterrupted.exit_code, 0) << uninterrupted.output;
  EXPECT_EQ(testing::deterministic_files(killed), testing::deterministic_files(whole));
  EXPECT_EQ(testing::read_all(killed, "scenarios").rows.size(), 60U);
  EXPECT_EQ(testing::read_manifest(killed)["shards"], testing::read_manifest(whole)["shards"]);
  for (const auto& e : fs::directory_iterator(killed)) {
    EXPECT_EQ(e.path().string().find(".tmp."), std::string::npos) << e.path();
  }
}

TEST(GenerateCli, MismatchedResumeExitsTwoAndChangesNothing) {
  TempDir dir;
  const std::string out = dir.file("d");
  testing::write_text(dir.file("c.json"), R"({"expert": {"weight_accel": 0.6}})");
  ASSERT_EQ(run_cli(small_run(out, 4, 1)).exit_code, 0);
  const auto before = testing::all_files(out);
  for (const std::string& args :
       {small_run(out, 4, 2), small_run(out, 5, 1), small_run(out, 4, 1, "--behavior idm"),
        small_run(out, 4, 1, "--time-limit 30"),
        small_run(out, 4, 1, "--config " + dir.file("c.json"))}) {
    const auto r = run_cli(args);
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.output;
    EXPECT_NE(r.output.find("another data set"), std::string::npos) << r.output;
  }
  EXPECT_EQ(testing::all_files(out), before);
}

TEST(GenerateCli, BadInputsExitTwoWithAMessage) {
  TempDir dir;
  testing::write_text(dir.file("file"), "x");
  testing::write_text(dir.file("bad.json"), "{not json");
  testing::write_text(dir.file("badvalue.json"), R"({"expert": {"steps": -3}})");
  fs::create_directories(dir.path() / "full");
  testing::write_text(dir.file("full/notes.txt"), "mine");
  const std::string out = dir.file("d");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {small_run(out, 0, 1), "--count"},
      {small_run(out, -3, 1), "--count"},
      {small_run(out, 3, 1, "--behavior warp"), "behavior"},
      {small_run(dir.file("file") + "/sub", 3, 1), "cannot create"},
      {small_run(dir.file("full"), 3, 1), "not empty"},
      {small_run(out, 3, 1, "--config " + dir.file("bad.json")), "not valid JSON"},
      {small_run(out, 3, 1, "--config " + dir.file("badvalue.json")), "expert.steps"},
      {small_run(out, 3, 1, "--config " + dir.file("absent.json")), "absent.json"},
      {small_run(out, 3, 1, "--solver nope"), "--solver"},
      {small_run(out, 3, 1, "--shard-size 0"), "--shard-size"},
  };
  for (const auto& [args, expected] : cases) {
    const auto r = run_cli(args);
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.output;
    EXPECT_NE(r.output.find(expected), std::string::npos) << args << "\n" << r.output;
  }
  EXPECT_FALSE(fs::exists(out));
  EXPECT_EQ(testing::read_text(dir.file("full/notes.txt")), "mine");
}

// Reads the "  name   count   share%" lines of one block of dataset-info's
// output. (No std::regex: GCC 12 warns inside it under the sanitizers.)
std::map<std::string, long long> printed_counts(const std::string& output,
                                                const std::string& title) {
  std::map<std::string, long long> counts;
  const std::size_t start = output.find(title + "\n");
  if (start == std::string::npos) return counts;
  std::istringstream in(output.substr(start + title.size() + 1));
  std::string line;
  while (std::getline(in, line) && line.rfind("  ", 0) == 0) {
    std::istringstream fields(line);
    std::string name;
    long long n = -1;
    fields >> name >> n;
    counts[name] = n;
  }
  return counts;
}

TEST(GenerateCli, DatasetInfoCountsWhatTheFilesHold) {
  TempDir dir;
  const std::string out = dir.file("d");
  ASSERT_EQ(run_cli(small_run(out, 13, 8)).exit_code, 0);
  const auto info = run_cli("dataset-info --data " + out);
  ASSERT_EQ(info.exit_code, 0) << info.output;
  const auto t = testing::read_all(out, "scenarios");
  std::map<std::string, long long> labels, behaviors;
  for (const auto& row : t.rows) {
    ++labels[row[t.column("label")]];
    ++behaviors[row[t.column("behavior")]];
  }
  EXPECT_EQ(printed_counts(info.output, "by label"), labels) << info.output;
  EXPECT_EQ(printed_counts(info.output, "by behavior"), behaviors) << info.output;
  const std::size_t at = info.output.find("p50 ");
  ASSERT_NE(at, std::string::npos) << info.output;
  double p50 = -1, p90 = -1, p99 = -1, max = -1;
  ASSERT_EQ(std::sscanf(info.output.c_str() + at, "p50 %lf, p90 %lf, p99 %lf, max %lf", &p50, &p90,
                        &p99, &max),
            4)
      << info.output;
  EXPECT_LE(p50, p90);
  EXPECT_LE(p90, p99);
  EXPECT_LE(p99, max);
  EXPECT_GT(max, 0.0);
}

TEST(GenerateCli, DatasetInfoRefusesWhatIsNotACompleteDataSet) {
  TempDir dir;
  const std::string out = dir.file("d");
  EXPECT_EQ(run_cli("dataset-info --data " + out).exit_code, 2);  // missing
  ASSERT_EQ(run_cli(small_run(out, 4, 3)).exit_code, 0);
  ASSERT_EQ(run_cli("dataset-info --data " + out).exit_code, 0);
  const std::string shard = out + "/scenarios-00000.csv";
  const std::string good = testing::read_text(shard);
  std::string changed = good;
  changed[changed.size() - 3] = changed[changed.size() - 3] == '1' ? '2' : '1';
  testing::write_text(shard, changed);
  const auto corrupt = run_cli("dataset-info --data " + out);
  EXPECT_EQ(corrupt.exit_code, 2);
  EXPECT_NE(corrupt.output.find("checksum"), std::string::npos) << corrupt.output;
  testing::write_text(shard, good);
  testing::write_text(out + "/manifest.json", "{\"format\": 3");
  EXPECT_EQ(run_cli("dataset-info --data " + out).exit_code, 2);
}

TEST(GenerateCli, MpiRanksWriteWhatThreadsWrite) {
#ifndef LANECHANGE_HAVE_MPI
  GTEST_SKIP() << "built without MPI";
#endif
  if (!testing::mpirun_available()) GTEST_SKIP() << "no mpirun";
  TempDir dir;
  const std::string threads = dir.file("threads");
  const std::string ranks = dir.file("ranks");
  ASSERT_EQ(run_cli(small_run(threads, 10, 6, "--jobs 2")).exit_code, 0);
  const auto on_ranks = testing::run_cli_on_ranks(2, small_run(ranks, 10, 6, "--jobs 1"));
  ASSERT_EQ(on_ranks.exit_code, 0) << on_ranks.output;
  const auto manifest = testing::read_manifest(ranks);
  EXPECT_EQ(manifest["run"]["ranks"], 2);
  EXPECT_EQ(testing::deterministic_files(threads), testing::deterministic_files(ranks));
  EXPECT_EQ(manifest["shards"], testing::read_manifest(threads)["shards"]);
}

}  // namespace
}  // namespace lanechange
