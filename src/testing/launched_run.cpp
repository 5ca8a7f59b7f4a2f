#include "sensornet/testing/launched_run.hpp"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <thread>

extern char** environ;

namespace sensornet::testing {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using Clock = std::chrono::steady_clock;
using namespace std::chrono_literals;

constexpr auto kStopGrace = 20s;  // the launcher's own grace for its processes is shorter

fs::path resolveProgram(const fs::path& given) {
  if (!given.empty()) return given;
  if (const char* env = std::getenv("SENSORNET_PROGRAM"); env != nullptr && *env != '\0') {
    return env;
  }
  if (const char* path = std::getenv("PATH"); path != nullptr) {
    std::stringstream dirs(path);
    std::string dir;
    while (std::getline(dirs, dir, ':')) {
      const fs::path candidate = fs::path(dir.empty() ? "." : dir) / "sensornet";
      if (::access(candidate.c_str(), X_OK) == 0) return candidate;
    }
  }
  throw std::runtime_error(
      "sensornet::testing: no sensornet program: set LaunchOptions::program "
      "(installedProgram() of <sensornet/testing/installed.hpp>), $SENSORNET_PROGRAM, or PATH");
}

// A run id no other test of this host uses now: this process, a counter, the clock.
std::string freshRunId() {
  static std::atomic<unsigned> counter{0};
  const auto ticks = Clock::now().time_since_epoch().count() % 1000000;
  return "fx-" + std::to_string(::getpid()) + "-" + std::to_string(counter++) + "-" +
         std::to_string(ticks);
}

fs::path privateFolder(const std::string& run_id) {
  const fs::path dir = fs::temp_directory_path() / ("sensornet-testing-" + run_id);
  fs::create_directories(dir);
  fs::permissions(dir, fs::perms::owner_all, fs::perm_options::replace);
  return dir;
}

std::string formatNumber(double value) {
  std::ostringstream out;
  out.precision(17);
  out << value;
  return out.str();
}

std::string joined(const std::vector<int>& ids) {
  std::string text;
  for (const int j : ids) text += (text.empty() ? "" : ",") + std::to_string(j);
  return text;
}

std::string slurp(const fs::path& path) {
  std::ifstream in(path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

std::optional<double> number(const json& node, const char* key) {
  if (!node.is_object() || !node.contains(key) || !node[key].is_number()) return std::nullopt;
  return node[key].get<double>();
}

std::vector<std::uint64_t> counts(const json& entry, const char* key) {
  std::vector<std::uint64_t> values;
  if (!entry.contains(key) || !entry[key].is_array()) return values;
  for (const json& v : entry[key]) values.push_back(v.is_number_unsigned() ? v.get<std::uint64_t>() : 0);
  return values;
}

}  // namespace

LaunchedRun::LaunchedRun(LaunchOptions options)
    : options_(std::move(options)), run_id_(freshRunId()) {
  if (options_.scenario.empty()) {
    throw std::invalid_argument("sensornet::testing: LaunchOptions::scenario is required");
  }
  const fs::path program = resolveProgram(options_.program);
  dir_ = privateFolder(run_id_);
  log_dir_ = dir_ / "logs";
  std::vector<std::string> argv = {program.string(),
                                   "launch",
                                   fs::absolute(options_.scenario).string(),
                                   "--episodes",
                                   std::to_string(options_.episodes),
                                   "--time-scale",
                                   formatNumber(options_.time_scale),
                                   "--seed",
                                   std::to_string(options_.seed),
                                   "--run-id",
                                   run_id_,
                                   "--log-dir",
                                   log_dir_.string(),
                                   "--report",
                                   (dir_ / "report.json").string(),
                                   "--no-html"};
  if (!options_.external_sensors.empty()) {
    argv.insert(argv.end(), {"--external-sensors", joined(options_.external_sensors)});
  }
  if (options_.external_fusion_center) argv.emplace_back("--external-fusion-center");
  if (options_.reference_fusion) argv.emplace_back("--reference-fusion");
  if (!options_.require.empty()) argv.insert(argv.end(), {"--require", options_.require});
  argv.insert(argv.end(), options_.extra_args.begin(), options_.extra_args.end());

  posix_spawn_file_actions_t files;
  posix_spawn_file_actions_init(&files);
  posix_spawn_file_actions_addopen(&files, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  const std::string out = (dir_ / "launcher.out").string();
  const std::string err = (dir_ / "launcher.err").string();
  posix_spawn_file_actions_addopen(&files, STDOUT_FILENO, out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
  posix_spawn_file_actions_addopen(&files, STDERR_FILENO, err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
  posix_spawnattr_t attributes;
  posix_spawnattr_init(&attributes);
  posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETPGROUP);  // its own group: stop() ends it
  posix_spawnattr_setpgroup(&attributes, 0);
  std::vector<char*> args;
  for (std::string& a : argv) args.push_back(a.data());
  args.push_back(nullptr);
  const int failed = ::posix_spawn(&pid_, args[0], &files, &attributes, args.data(), environ);
  posix_spawn_file_actions_destroy(&files);
  posix_spawnattr_destroy(&attributes);
  if (failed != 0) {
    pid_ = -1;
    std::error_code ignored;
    fs::remove_all(dir_, ignored);
    throw std::runtime_error("sensornet::testing: cannot start " + program.string() + ": " +
                             std::strerror(failed));
  }
}

LaunchedRun::~LaunchedRun() {
  if (pid_ > 0 && !result_) stop();
  if (!keep_files_) {
    std::error_code ignored;
    fs::remove_all(dir_, ignored);
  }
}

// Ctrl-C to the launcher, as a user stops a run; its process group killed if it lingers.
void LaunchedRun::stop() {
  ::kill(pid_, SIGINT);
  const auto until = Clock::now() + kStopGrace;
  int status = 0;
  while (::waitpid(pid_, &status, WNOHANG) == 0) {
    if (Clock::now() >= until) {
      ::kill(-pid_, SIGKILL);
      (void)::waitpid(pid_, &status, 0);
      break;
    }
    std::this_thread::sleep_for(20ms);
  }
  pid_ = -1;
}

const RunResult& LaunchedRun::wait() {
  if (result_) return *result_;
  const auto until = Clock::now() + options_.timeout;
  int status = 0;
  pid_t done = 0;
  while ((done = ::waitpid(pid_, &status, WNOHANG)) == 0 && Clock::now() < until) {
    std::this_thread::sleep_for(20ms);
  }
  if (done != pid_) {  // timed out: the run is stopped, and says so in its report
    ::kill(pid_, SIGINT);
    (void)::waitpid(pid_, &status, 0);
  }
  pid_ = -1;
  result_ = read(WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status));
  return *result_;
}

RunResult LaunchedRun::read(int exit_code) const {
  RunResult r;
  r.exit_code = exit_code;
  r.output = slurp(dir_ / "launcher.out");
  r.errors = slurp(dir_ / "launcher.err");
  std::ifstream in(dir_ / "report.json");
  r.report = json::parse(in, nullptr, false);
  if (!r.report.is_object()) {
    r.report = json::object();
    return r;
  }
  r.status = r.report.value("status", std::string());
  const json summary = r.report.value("summary", json::object());
  r.mean = number(summary, "mean");
  const json bracket = summary.value("bracket", json::object());
  r.bracket_lower = number(bracket, "info");
  r.bracket_upper = number(bracket, "cov");
  if (summary.contains("meets_bracket") && summary["meets_bracket"].is_boolean()) {
    r.meets_bracket = summary["meets_bracket"].get<bool>();
  }
  r.fusion_agreement =
      number(r.report.value("reference_fusion", json::object()), "max_relative_difference");
  for (const json& e : r.report.value("per_episode", json::array())) {
    EpisodeResult episode;
    episode.episode = e.value("episode", 0u);
    episode.realized_cost = number(e, "realized_cost");
    episode.complete = e.value("complete", false);
    if (e.contains("incomplete_reason") && e["incomplete_reason"].is_string()) {
      episode.incomplete_reason = e["incomplete_reason"].get<std::string>();
    }
    episode.sent = counts(e, "sent");
    episode.received = counts(e, "received");
    episode.lost = counts(e, "lost");
    r.episodes.push_back(std::move(episode));
  }
  for (const json& f : r.report.value("faults", json::array())) {
    r.faults.push_back(f.value("kind", std::string()) + " in " + f.value("process", std::string()) +
                       ": " + f.value("detail", std::string()));
  }
  return r;
}

}  // namespace sensornet::testing
