// chaos: randomized fault schedules against whole `sensornet launch` runs, and the invariants
// that must hold after each (tests/chaos/README.md).
//
//   chaos --seed 42                     # one trial, replayed from its seed
//   chaos --trials 50 --first-seed 100  # a sweep: seeds 100..149
//   chaos --seeds 3,17,29               # the fixed set CTest runs
//
// Each trial prints one line: its seed, the run and its faults, and OK or every violated
// invariant. The exit status is 0 when no trial violated anything, 1 otherwise, 2 on bad usage.

#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "fault_schedule.hpp"
#include "invariants.hpp"
#include "support/background_process.hpp"
#include "support/faketime.hpp"
#include "support/netns_hosts.hpp"
#include "support/process.hpp"

namespace sensornet::chaos {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using Clock = std::chrono::steady_clock;

constexpr auto kPoll = std::chrono::milliseconds(10);

// Ctrl-C or SIGTERM of chaos itself: the trial under way is stopped and cleaned up (its
// processes, its namespaces, links and rules), and no further trial starts.
volatile std::sig_atomic_t g_stop = 0;
extern "C" void onStopSignal(int /*signal*/) { g_stop = 1; }
// After the launcher ended, its children may take this long to go (README: after kill -9 of the
// launcher they outlive it by 2-4 s; the parent-death signal, then their own shutdown).
constexpr double kLeftoverGraceS = 12.0;
// Episodes of the clean runs the costs are compared with (every trial has at most 9).
constexpr int kCleanEpisodes = 9;

struct Options {
  std::vector<std::uint64_t> seeds;
  std::string launcher = SENSORNET_LAUNCHER;
  fs::path source_dir = SENSORNET_SOURCE_DIR;
  fs::path work;   // trial folders; default: a fresh folder in /tmp
  fs::path cache;  // clean runs' costs; default: <work>/clean
  bool keep = false;
  bool list = false;  // print the trials the seeds draw, run nothing
  bool network = true;  // --no-network: process faults only, as drawn before network trials
};

std::string readText(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

double secondsSince(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

std::int64_t realtimeNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

std::string cmdlineOf(pid_t pid) {
  std::string cmdline = readText("/proc/" + std::to_string(pid) + "/cmdline");
  for (char& c : cmdline) c = c == '\0' ? ' ' : c;
  return cmdline;
}

// The run's process of `target` (for a sensor agent: the one hosting sensor `agent`).
std::optional<pid_t> processOf(const std::string& run_id, Target target, int agent) {
  static const std::map<Target, std::string> kProgram = {{Target::Coordinator, "coordinator"},
                                                         {Target::FusionCenter, "fusion_center"},
                                                         {Target::SensorAgent, "sensor_agent"},
                                                         {Target::Launcher, "sensornet"}};
  for (const pid_t pid : testing::processesMentioning(run_id)) {
    std::istringstream words(cmdlineOf(pid));
    std::vector<std::string> argv;
    for (std::string w; words >> w;) argv.push_back(w);
    if (argv.empty() || fs::path(argv[0]).filename() != kProgram.at(target)) continue;
    if (!testing::processExists(pid)) continue;
    if (target != Target::SensorAgent) return pid;
    const auto flag = std::find(argv.begin(), argv.end(), "--sensors");
    if (flag != argv.end() && flag + 1 != argv.end() && *(flag + 1) == std::to_string(agent)) {
      return pid;
    }
  }
  return std::nullopt;
}

// Whether `pid` has a handler for `signal` (SigCgt of /proc/PID/status).
bool catches(pid_t pid, int signal) {
  std::istringstream status(readText("/proc/" + std::to_string(pid) + "/status"));
  for (std::string line; std::getline(status, line);) {
    if (line.rfind("SigCgt:", 0) != 0) continue;
    const unsigned long long mask = std::strtoull(line.c_str() + 7, nullptr, 16);
    return ((mask >> (signal - 1)) & 1ULL) != 0;
  }
  return false;
}

std::size_t logLineCount(const fs::path& log) {
  const std::string text = readText(log);
  return static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n'));
}

// The coordinator's journal: the episode announced last and its start (realtime ns).
std::optional<std::pair<int, std::int64_t>> announced(const fs::path& journal) {
  const json j = json::parse(readText(journal), nullptr, false);
  if (!j.is_object() || !j.contains("announced") || !field(j, "announced").is_object()) return std::nullopt;
  const json& a = field(j, "announced");
  if (!field(a, "episode").is_number_integer() || !field(a, "start_wall_ns").is_number_integer()) return std::nullopt;
  return std::make_pair(field(a, "episode").get<int>(), field(a, "start_wall_ns").get<std::int64_t>());
}

std::string scenarioPath(const Options& o, const Trial& t, const fs::path& dir) {
  switch (t.scenario) {
    case ScenarioKind::Default: return (o.source_dir / "scenarios/default.yaml").string();
    case ScenarioKind::Lossy: return (o.source_dir / "scenarios/lossy.yaml").string();
    case ScenarioKind::Small: {
      const fs::path path = dir / "small.yaml";
      std::ofstream(path) << smallScenarioYaml(t);
      return path.string();
    }
  }
  return {};
}

std::vector<std::string> launchArgs(const Options& o, const std::string& scenario, int episodes,
                                    double time_scale, const std::string& policy,
                                    std::uint64_t seed, const std::string& run_id,
                                    const fs::path& dir) {
  char scale[32];
  std::snprintf(scale, sizeof scale, "%g", time_scale);
  return {o.launcher,      "launch",       scenario,
          "--episodes",    std::to_string(episodes),
          "--time-scale",  scale,
          "--seed",        std::to_string(seed),
          "--on-sensor-failure", policy,
          "--run-id",      run_id,
          "--report",      (dir / "report.json").string(),
          "--log-dir",     (dir / "logs").string(),
          "--no-html"};
}

// Kills whatever of the run still runs, after the grace; returns their command lines.
std::vector<std::string> reapLeftovers(const std::string& run_id) {
  const auto t0 = Clock::now();
  std::vector<pid_t> left;
  do {
    left = testing::processesMentioning(run_id);
    left.erase(std::remove_if(left.begin(), left.end(),
                              [](pid_t p) { return !testing::processExists(p); }),
               left.end());
    if (left.empty()) return {};
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  } while (secondsSince(t0) < kLeftoverGraceS);
  std::vector<std::string> lines;
  for (const pid_t pid : left) {
    lines.push_back(cmdlineOf(pid).substr(0, 120));
    ::kill(pid, SIGCONT);
    ::kill(pid, SIGKILL);
  }
  return lines;
}

// Network trials: the coordinator on host 1, the fusion center on host 2, the first half of the
// sensors on host 3 ("edge-1"), the rest on host 4 ("edge-2").
constexpr int kCoordinatorHost = 1;
constexpr int kFusionHost = 2;
int sensorHost(int host) { return 3 + host; }

// Sensor hosts with a clock fault run their processes under libfaketime, reading their offset
// from a file (FAKETIME_TIMESTAMP_FILE, re-read each second) that a step rewrites; their
// monotonic clock is left alone, as NTP leaves it.
struct Clocks {
  std::string library;                  // libfaketime.so.1
  std::map<int, fs::path> offset_file;  // sensor host (0, 1) -> its offset file
};

void writeOffset(const fs::path& file, double seconds) {
  char text[32];
  std::snprintf(text, sizeof text, "%+.3f\n", seconds);
  std::ofstream(file) << text;
}

std::string hostsYaml(const Trial& t, const testing::NetnsHosts& hosts, const Clocks& clocks) {
  std::string text = "hosts:\n";
  const auto host = [&](int i, const std::string& name, const std::string& runs) {
    std::string exec = "ip netns exec " + hosts.ns(i);
    for (const auto& [h, file] : clocks.offset_file) {
      if (sensorHost(h) != i) continue;
      exec = "env " +
             testing::faketimeEnvironment(clocks.library, "FAKETIME_TIMESTAMP_FILE=" + file.string() +
                                                              " FAKETIME_CACHE_DURATION=1") +
             " " + exec;
    }
    text += "  - name: " + name + "\n    address: " + hosts.address(i) + "\n    exec: " + exec + "\n" + runs;
  };
  const int half = t.sensors / 2;
  host(kCoordinatorHost, "control", "    coordinator: true\n");
  host(kFusionHost, "fusion", "    fusion_center: true\n");
  host(sensorHost(0), "edge-1", "    sensors: 0-" + std::to_string(half - 1) + "\n");
  host(sensorHost(1), "edge-2",
       "    sensors: " + std::to_string(half) + "-" + std::to_string(t.sensors - 1) + "\n");
  return text;
}

using Argv = std::vector<std::string>;

Argv inNamespace(const testing::NetnsHosts& hosts, int host, Argv command) {
  Argv argv = {"/usr/bin/env", "ip", "netns", "exec", hosts.ns(host)};
  argv.insert(argv.end(), command.begin(), command.end());
  return argv;
}

// A network fault struck: the commands that heal it, and how it was made.
struct Struck {
  std::vector<Argv> heal;
  std::string how;
  std::string failed;  // the command that failed, and why (nothing was left applied)
};

// Strikes a network fault on the sensor host's link (iptables rules in the namespaces, the
// link's state, a qdisc); every command that succeeded has its undoing in `heal`.
Struck strikeNetwork(const PlannedFault& p, const testing::NetnsHosts& hosts) {
  Struck out;
  const int host = sensorHost(p.host);
  const std::string address = hosts.address(host);
  const auto run = [&](const Argv& apply, Argv heal) {
    if (!out.failed.empty()) return false;
    const testing::ProcessResult r = testing::runProcess(apply, std::chrono::seconds(10));
    if (r.exit_code != 0) {
      std::string command;
      for (std::size_t i = 1; i < apply.size(); ++i) command += (i > 1 ? " " : "") + apply[i];
      out.failed = command + ": " + r.err.substr(0, r.err.find('\n'));
      return false;
    }
    if (!heal.empty()) out.heal.insert(out.heal.begin(), std::move(heal));
    return true;
  };
  const auto rule = [&](int ns, const std::string& chain, Argv match) {
    Argv insert = {"iptables", "-I", chain};
    insert.insert(insert.end(), match.begin(), match.end());
    Argv remove = insert;
    remove[1] = "-D";
    run(inNamespace(hosts, ns, insert), inNamespace(hosts, ns, remove));
  };
  char probability[32];
  std::snprintf(probability, sizeof probability, "%.3f", p.loss);
  switch (p.action) {
    case Action::CutLink:
      run({"/usr/bin/env", "ip", "link", "set", hosts.veth(host), "down"},
          {"/usr/bin/env", "ip", "link", "set", hosts.veth(host), "up"});
      out.how = "link down";
      break;
    case Action::FusionDeaf:
      rule(kFusionHost, "INPUT", {"-s", address, "-j", "DROP"});
      out.how = "iptables";
      break;
    case Action::HostDeaf:
      rule(host, "INPUT", {"-s", hosts.address(kCoordinatorHost), "-j", "DROP"});
      out.how = "iptables";
      break;
    case Action::LossBurst:
      rule(host, "INPUT", {"-m", "statistic", "--mode", "random", "--probability", probability, "-j", "DROP"});
      for (const int ns : {kCoordinatorHost, kFusionHost}) {
        rule(ns, "INPUT",
             {"-s", address, "-m", "statistic", "--mode", "random", "--probability", probability, "-j", "DROP"});
      }
      out.how = "iptables statistic";
      break;
    case Action::ReorderBurst: {
      // netem where the kernel has it; else 30% of the packets through a 1 Mbit/s class of an
      // HTB qdisc, chosen by iptables' statistic match: they queue behind one another and
      // arrive after packets sent later through the fast class.
      const Argv del = inNamespace(hosts, host, {"tc", "qdisc", "del", "dev", "eth0", "root"});
      if (testing::runProcess(inNamespace(hosts, host, {"tc", "qdisc", "add", "dev", "eth0", "root",
                                                         "netem", "delay", "10ms", "reorder", "50%"}),
                              std::chrono::seconds(10))
              .exit_code == 0) {
        out.heal.push_back(del);
        out.how = "netem";
        break;
      }
      out.how = "htb";
      run(inNamespace(hosts, host, {"tc", "qdisc", "add", "dev", "eth0", "root", "handle", "1:", "htb",
                                    "default", "10", "r2q", "1000"}),
          del);
      run(inNamespace(hosts, host, {"tc", "class", "add", "dev", "eth0", "parent", "1:", "classid",
                                    "1:10", "htb", "rate", "1gbit"}),
          {});
      run(inNamespace(hosts, host, {"tc", "class", "add", "dev", "eth0", "parent", "1:", "classid",
                                    "1:20", "htb", "rate", "1mbit", "ceil", "1mbit"}),
          {});
      Argv classify = {"iptables", "-t", "mangle", "-I", "POSTROUTING", "-o", "eth0", "-m", "statistic",
                       "--mode", "random", "--probability", "0.3", "-j", "CLASSIFY", "--set-class", "1:20"};
      Argv unclassify = classify;
      unclassify[3] = "-D";
      run(inNamespace(hosts, host, classify), inNamespace(hosts, host, unclassify));
      break;
    }
    default: out.failed = "not a network fault"; break;
  }
  if (!out.failed.empty()) {
    for (const Argv& heal : out.heal) (void)testing::runProcess(heal, std::chrono::seconds(10));
    out.heal.clear();
  }
  return out;
}

std::string uniqueRunId(std::uint64_t seed, const char* what) {
  char id[64];
  std::snprintf(id, sizeof id, "chaos-%d-%s-%llx", static_cast<int>(::getpid()), what,
                static_cast<unsigned long long>(seed));
  return id;
}

// The clean run's realized costs per episode (null where incomplete), cached per scenario and
// run seed: costs depend on neither the episode count nor the time scale.
std::vector<std::optional<double>> cleanCosts(const Options& o, const Trial& t) {
  const std::string key = std::string(nameOf(t.scenario)) +
                          (t.scenario == ScenarioKind::Small ? std::to_string(t.small_scenario_seed) : "") +
                          "-seed" + std::to_string(t.run_seed);
  const fs::path cached = o.cache / (key + ".json");
  json costs = json::parse(readText(cached), nullptr, false);
  if (!costs.is_array()) {
    const fs::path dir = o.cache / key;
    fs::create_directories(dir);
    const std::string run_id = uniqueRunId(t.run_seed, ("clean-" + key).c_str());
    testing::BackgroundProcess run(
        launchArgs(o, scenarioPath(o, t, dir), kCleanEpisodes, 3.0, "replan", t.run_seed, run_id, dir),
        (dir / "launch.log").string());
    if (!run.waitForExit(std::chrono::seconds(240))) (void)run.stop();
    (void)reapLeftovers(run_id);
    const json report = json::parse(readText(dir / "report.json"), nullptr, false);
    costs = json::array();
    if (report.is_object() && field(report, "per_episode").is_array()) {
      for (const json& e : field(report, "per_episode")) {
        const auto k = e.value("episode", std::size_t{0});
        if (costs.size() <= k) costs.insert(costs.end(), k + 1 - costs.size(), nullptr);
        costs[k] = e.value("complete", false) ? field(e, "realized_cost") : json(nullptr);
      }
    }
    std::ofstream(cached) << costs.dump() << '\n';
  }
  std::vector<std::optional<double>> out;
  for (const json& c : costs) out.push_back(c.is_number() ? std::optional(c.get<double>()) : std::nullopt);
  return out;
}

struct PendingCont {
  pid_t pid;
  Clock::time_point at;
};

struct PendingHeal {
  std::vector<Argv> commands;
  Clock::time_point at;
  int cut_host = -1;   // CutLink: the host whose link comes up when no other cut of it lasts
  std::size_t fault;   // its index in the trial record
};

// Heals a network fault; a link cut twice at once comes up when its last cut ends (with the
// commands of whichever cut brought it down: every cut of a host carries the same undoing).
// Returns whether the fault's silence ended now.
bool heal(const PendingHeal& h, std::map<int, int>& cuts) {
  if (h.cut_host >= 0 && --cuts[h.cut_host] > 0) return false;
  for (const Argv& command : h.commands) (void)testing::runProcess(command, std::chrono::seconds(10));
  return true;
}

// When each fault of `record` healed (seconds after the launch): every cut of a host heals
// when its link comes up.
void noteHealed(TrialRecord& record, const PendingHeal& h, double at_s) {
  record.faults[h.fault].healed_at_s = at_s;
  if (h.cut_host < 0) return;
  for (InjectedFault& f : record.faults) {
    if (f.injected && f.planned.action == Action::CutLink && f.planned.host == h.cut_host &&
        f.healed_at_s < 0.0) {
      f.healed_at_s = at_s;
    }
  }
}

// Runs the trial's launch, strikes its faults when their moments come, and collects what the
// invariants are checked on.
TrialRecord runTrial(const Options& o, const Trial& t, const fs::path& dir) {
  TrialRecord r;
  r.trial = t;
  r.clean_costs = cleanCosts(o, t);
  fs::create_directories(dir);
  const std::string run_id = uniqueRunId(t.seed, "t");
  const fs::path log = dir / "report.jsonl";
  const fs::path journal = dir / "logs" / "coordinator-state.json";
  for (const PlannedFault& p : t.faults) {
    InjectedFault f;
    f.planned = p;
    r.faults.push_back(std::move(f));
  }

  std::optional<testing::NetnsHosts> hosts;
  std::map<int, fs::path> offset_files;  // sensor host -> its clock's offset file
  std::vector<std::string> args =
      launchArgs(o, scenarioPath(o, t, dir), t.episodes, t.time_scale, t.policy, t.run_seed, run_id, dir);
  if (t.on_hosts) {
    if (const auto why = testing::NetnsHosts::unavailable()) {
      r.skipped = "a network trial, and " + *why;
      return r;
    }
    Clocks clocks;
    for (const PlannedFault& p : t.faults) {
      if (!isClockFault(p.action)) continue;
      const auto library = testing::faketimeLibrary();
      if (!library) {
        r.skipped = "a clock fault, and libfaketime is not installed (Debian: faketime)";
        return r;
      }
      clocks.library = *library;
      const fs::path file = dir / ("clock-edge-" + std::to_string(p.host + 1));
      writeOffset(file, p.action == Action::ClockOffset ? p.clock_s : 0.0);
      clocks.offset_file[p.host] = file;
    }
    offset_files = clocks.offset_file;
    hosts.emplace(4);
    const fs::path file = dir / "hosts.yaml";
    std::ofstream(file) << hostsYaml(t, *hosts, clocks);
    args.insert(args.end(), {"--hosts", file.string()});
  }

  const auto t0 = Clock::now();
  const std::int64_t t0_realtime_ns = realtimeNs();
  testing::BackgroundProcess launcher(args, (dir / "launch.log").string());
  double stops = 0.0;
  for (const PlannedFault& p : t.faults) stops += p.length_s;
  const double limit_s = 90.0 + 3.0 * t.episodes * t.episodeWallS() + stops;

  std::map<Target, Clock::time_point> first_seen = {{Target::Launcher, t0}};
  std::map<int, std::int64_t> starts;  // episode -> announced start (realtime ns)
  std::vector<PendingCont> conts;
  std::vector<PendingHeal> heals;
  std::map<int, int> cuts;  // sensor host -> cuts of its link in force
  std::optional<int> exit_code;
  std::vector<bool> dead_agents(static_cast<std::size_t>(t.sensors), false);
  while (!exit_code && secondsSince(t0) < limit_s && g_stop == 0) {
    exit_code = launcher.waitForExit(std::chrono::milliseconds(0));
    if (exit_code) break;
    for (const Target target : {Target::Coordinator, Target::FusionCenter, Target::SensorAgent}) {
      if (first_seen.count(target) == 0) {
        for (int a = 0; a < t.sensors; ++a) {
          if (processOf(run_id, target, a)) {
            first_seen[target] = Clock::now();
            break;
          }
          if (target != Target::SensorAgent) break;
        }
      }
    }
    if (const auto a = announced(journal)) {
      if (starts.count(a->first) == 0) {
        // An episode announced while an earlier one's announcement went unseen: back to back.
        for (int k = a->first - 1; k >= 0 && starts.count(k) == 0; --k) {
          starts[k] = a->second - static_cast<std::int64_t>((a->first - k) * (t.episodeWallS() + 0.002) * 1e9);
        }
        starts[a->first] = a->second;
      }
    }
    for (InjectedFault& f : r.faults) {
      if (f.injected || !f.note.empty()) continue;
      const PlannedFault& p = f.planned;
      bool due = false;
      if (p.anchor == Anchor::Launch) {
        const auto seen =
            first_seen.find(p.target == Target::SensorHost ? Target::SensorAgent : p.target);
        due = seen != first_seen.end() &&
              std::chrono::duration<double>(Clock::now() - seen->second).count() >= p.offset_s;
      } else {
        const auto start = starts.find(p.episode);
        due = start != starts.end() &&
              realtimeNs() >= start->second + static_cast<std::int64_t>(p.offset_s * 1e9);
      }
      if (!due) continue;
      if (isClockFault(p.action)) {  // an offset in force from the start, or a step now
        f.at_s = secondsSince(t0);
        f.logged_before = logLineCount(log);
        if (p.action == Action::ClockStep) writeOffset(offset_files.at(p.host), p.clock_s);
        f.injected = true;
        f.note = "faketime";
        continue;
      }
      if (p.target == Target::SensorHost) {
        f.at_s = secondsSince(t0);
        f.logged_before = logLineCount(log);
        const bool cut = p.action == Action::CutLink;
        const std::size_t index = static_cast<std::size_t>(&f - r.faults.data());
        if (cut && cuts[p.host]++ > 0) {  // already down: this cut lengthens it
          f.injected = true;
          f.note = "link down";
          heals.push_back({{{"/usr/bin/env", "ip", "link", "set", hosts->veth(sensorHost(p.host)), "up"}},
                           Clock::now() + std::chrono::milliseconds(static_cast<int>(p.length_s * 1000)),
                           p.host, index});
          continue;
        }
        const Struck struck = strikeNetwork(p, *hosts);
        if (!struck.failed.empty()) {
          if (cut) --cuts[p.host];
          f.note = "failed: " + struck.failed;
          continue;
        }
        f.injected = true;
        f.note = struck.how;
        heals.push_back({struck.heal, Clock::now() + std::chrono::milliseconds(static_cast<int>(p.length_s * 1000)),
                         cut ? p.host : -1, index});
        continue;
      }
      std::optional<pid_t> pid;
      if (p.target == Target::Launcher) {
        pid = launcher.pid();
      } else if (p.target == Target::SensorAgent) {
        for (int i = 0; i < t.sensors && !pid; ++i) {  // the planned agent, else the next alive
          const int a = (p.agent + i) % t.sensors;
          if (p.action == Action::Kill && dead_agents[static_cast<std::size_t>(a)]) continue;
          pid = processOf(run_id, p.target, a);
          if (pid) f.agent = a;
        }
      } else {
        pid = processOf(run_id, p.target, 0);
      }
      if (!pid) {
        f.note = "no such process";
        continue;
      }
      f.at_s = secondsSince(t0);
      f.logged_before = logLineCount(log);
      const int signal = p.action == Action::Stop        ? SIGSTOP
                         : p.action == Action::Interrupt ? SIGINT
                         : p.action == Action::Terminate ? SIGTERM
                                                         : SIGKILL;
      // A signal that comes before the launcher's main() could install its handlers (the
      // loader maps its libraries first, ~10 ms) kills it whatever the program does: no user
      // is that fast, and no program can answer it. Such a moment waits for the handlers.
      if (p.target == Target::Launcher && signal != SIGKILL && signal != SIGSTOP) {
        const auto give_up = Clock::now() + std::chrono::seconds(2);
        while (!catches(*pid, signal) && Clock::now() < give_up) std::this_thread::sleep_for(kPoll / 10);
      }
      if (::kill(*pid, signal) != 0) {
        f.note = "kill failed";
        continue;
      }
      f.injected = true;
      f.note = "pid " + std::to_string(*pid);
      if (p.action == Action::Stop) {
        conts.push_back({*pid, Clock::now() + std::chrono::milliseconds(static_cast<int>(p.length_s * 1000))});
      }
      if (p.target == Target::SensorAgent && p.action == Action::Kill) {
        dead_agents[static_cast<std::size_t>(f.agent)] = true;
      }
    }
    for (auto it = heals.begin(); it != heals.end();) {
      if (Clock::now() >= it->at) {
        if (heal(*it, cuts)) noteHealed(r, *it, secondsSince(t0));
        it = heals.erase(it);
      } else {
        ++it;
      }
    }
    for (auto it = conts.begin(); it != conts.end();) {
      if (Clock::now() >= it->at) {
        ::kill(it->pid, SIGCONT);
        it = conts.erase(it);
      } else {
        ++it;
      }
    }
    std::this_thread::sleep_for(kPoll);
  }
  for (const PendingCont& c : conts) ::kill(c.pid, SIGCONT);  // nothing stays stopped
  r.ended_at_s = secondsSince(t0);
  for (const PendingHeal& h : heals) {  // nor cut off
    if (heal(h, cuts)) noteHealed(r, h, secondsSince(t0));
  }
  if (g_stop != 0) r.skipped = "chaos was interrupted";
  if (!exit_code) {
    r.ended = false;
    ::kill(launcher.pid(), SIGCONT);
    exit_code = launcher.stop(std::chrono::milliseconds(10000));
  }
  r.exit_code = *exit_code;
  for (InjectedFault& f : r.faults) {
    if (!f.injected && f.note.empty()) f.note = "the run had ended";
  }
  r.leftovers = reapLeftovers(run_id);
  hosts.reset();  // the namespaces, their links and rules go
  r.report_exists = fs::exists(dir / "report.json");
  struct stat written {};
  if (r.report_exists && ::stat((dir / "report.json").c_str(), &written) == 0) {
    const std::int64_t at_ns = static_cast<std::int64_t>(written.st_mtim.tv_sec) * 1'000'000'000 + written.st_mtim.tv_nsec;
    r.report_written_at_s = 1e-9 * static_cast<double>(at_ns - t0_realtime_ns);
  }
  json report = json::parse(readText(dir / "report.json"), nullptr, false);
  if (report.is_object()) r.report = std::move(report);
  r.episode_log = readText(log);
  return r;
}

std::string outcomeLine(const TrialRecord& r, const std::vector<std::string>& violations) {
  std::string line = "seed " + std::to_string(r.trial.seed) + " [" + describe(r.trial) + "]";
  if (!r.skipped.empty()) return line + ": SKIPPED (" + r.skipped + ")";
  std::string notes;
  for (const InjectedFault& f : r.faults) {
    char at[48];
    std::snprintf(at, sizeof at, "at %.2f s", f.at_s);
    notes += (notes.empty() ? "" : ", ") +
             (f.injected ? std::string(at) + (f.planned.target == Target::SensorAgent
                                                   ? " (sensor_agent-" + std::to_string(f.agent) + ")"
                                               : f.planned.target == Target::SensorHost
                                                   ? " (" + f.note + ")"
                                                   : std::string())
                         : "not injected: " + f.note);
  }
  line += " {" + notes + "} -> exit " + std::to_string(r.exit_code);
  if (r.report) line += " " + r.report->value("status", std::string("?"));
  if (violations.empty()) return line + ": OK";
  line += ": VIOLATED";
  for (const std::string& v : violations) line += " | " + v;
  return line;
}

int usage(const std::string& why) {
  std::cerr << "chaos: " << why << "\n"
            << "usage: chaos (--seed S | --seeds S1,S2,... | --trials N [--first-seed S])\n"
            << "             [--launcher PATH] [--source-dir DIR] [--work DIR] [--cache DIR] [--keep] [--list]\n"
            << "             [--no-network]   # process faults only: the trials seeds drew before network faults\n";
  return 2;
}

std::optional<std::uint64_t> parseSeed(const std::string& text) {
  if (text.empty() || text.front() == '-') return std::nullopt;
  char* end = nullptr;
  errno = 0;
  const unsigned long long v = std::strtoull(text.c_str(), &end, 0);
  if (errno != 0 || *end != '\0') return std::nullopt;
  return v;
}

}  // namespace
}  // namespace sensornet::chaos

int main(int argc, char** argv) {
  using namespace sensornet::chaos;
  Options o;
  std::optional<std::uint64_t> trials;
  std::uint64_t first = 1;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const auto value = [&]() -> std::string { return i + 1 < argc ? argv[++i] : ""; };
    if (arg == "--help" || arg == "-h") {
      (void)usage("randomized fault schedules against sensornet launch (tests/chaos/README.md)");
      return 0;
    } else if (arg == "--seed" || arg == "--seeds") {
      std::istringstream list(value());
      for (std::string s; std::getline(list, s, ',');) {
        const auto seed = parseSeed(s);
        if (!seed) return usage(arg + ": expected seeds (decimal or 0x hex), got '" + s + "'");
        o.seeds.push_back(*seed);
      }
      if (o.seeds.empty()) return usage(arg + ": expected a seed");
    } else if (arg == "--trials" || arg == "--first-seed") {
      const auto n = parseSeed(value());
      if (!n) return usage(arg + ": expected a non-negative integer");
      if (arg == "--trials") {
        trials = *n;
      } else {
        first = *n;
      }
    } else if (arg == "--launcher") {
      o.launcher = value();
    } else if (arg == "--source-dir") {
      o.source_dir = value();
    } else if (arg == "--work") {
      o.work = value();
    } else if (arg == "--cache") {
      o.cache = value();
    } else if (arg == "--keep") {
      o.keep = true;
    } else if (arg == "--list") {
      o.list = true;
    } else if (arg == "--no-network") {
      o.network = false;
    } else {
      return usage("unknown option " + arg);
    }
  }
  if (trials) {
    for (std::uint64_t k = 0; k < *trials; ++k) o.seeds.push_back(first + k);
  }
  if (o.seeds.empty()) return usage("no trial: give --seed, --seeds or --trials");
  if (o.list) {
    for (const std::uint64_t seed : o.seeds) {
      std::cout << "seed " << seed << " [" << describe(drawTrial(seed, o.network)) << "]\n";
    }
    return 0;
  }
  namespace fs = std::filesystem;
  const bool own_work = o.work.empty();
  if (own_work) {
    char pattern[] = "/tmp/sensornet-chaos-XXXXXX";
    if (::mkdtemp(pattern) == nullptr) return usage("cannot make a folder in /tmp");
    o.work = pattern;
  }
  if (o.cache.empty()) o.cache = o.work / "clean";
  fs::create_directories(o.cache);
  // The launcher's scratch folder and current-run record go in the work folder, never the user's.
  ::setenv("XDG_RUNTIME_DIR", o.work.c_str(), 1);
  ::setenv("SENSORNET_SCRATCH_DIR", (o.work / "scratch").c_str(), 1);
  ::unsetenv("SENSORNET_CYCLONE_CONFIG");
  // A shell starts background jobs with SIGINT ignored, and the launcher would inherit that:
  // its signals must be the defaults a user's terminal gives it. Handled signals are reset to
  // the defaults in every program chaos starts (exec); ignored ones would not be.
  for (const int signal : {SIGINT, SIGTERM}) ::signal(signal, onStopSignal);

  int violated = 0;
  int skipped = 0;
  std::size_t ran = 0;  // trials begun (an interrupt ends the list early)
  std::size_t injected = 0;
  std::map<std::string, int> kinds;
  for (const std::uint64_t seed : o.seeds) {
    if (g_stop != 0) break;
    ++ran;
    const Trial trial = drawTrial(seed, o.network);
    const fs::path dir = o.work / ("trial-" + std::to_string(seed));
    std::error_code ignored;
    fs::remove_all(dir, ignored);
    const auto began = Clock::now();
    const TrialRecord record = runTrial(o, trial, dir);
    sensornet::testing::removeStaleFaketimeFiles();  // of the clock-faulted processes it killed
    if (!record.skipped.empty()) {
      ++skipped;
      std::cout << outcomeLine(record, {}) << std::endl;
      fs::remove_all(dir, ignored);
      continue;
    }
    const std::vector<std::string> violations = checkInvariants(record);
    char took[32];
    std::snprintf(took, sizeof took, " (%.0f s)", secondsSince(began));
    std::cout << outcomeLine(record, violations) << took << std::endl;
    for (const InjectedFault& f : record.faults) {
      if (!f.injected) continue;
      ++injected;
      // "kill -9 fusion_center"; a host's link or clock by the fault alone ("cut", "clock step")
      ++kinds[std::string(nameOf(f.planned.action)) +
              (f.planned.target == Target::SensorHost ? "" : std::string(" ") + nameOf(f.planned.target))];
    }
    if (!violations.empty()) {
      ++violated;
      std::cout << "  kept: " << dir.string() << std::endl;
    } else if (!o.keep) {
      fs::remove_all(dir, ignored);
    }
  }
  std::cout << ran << " trial(s)" << (ran < o.seeds.size() ? " of " + std::to_string(o.seeds.size()) : "") << ", " << injected << " fault(s) injected (";
  bool first_kind = true;
  for (const auto& [kind, n] : kinds) {
    std::cout << (first_kind ? "" : ", ") << n << " " << kind;
    first_kind = false;
  }
  std::cout << "), " << violated << " with violations";
  if (skipped > 0) std::cout << ", " << skipped << " skipped";
  std::cout << std::endl;
  if (own_work && violated == 0 && !o.keep) {
    std::error_code ignored;
    fs::remove_all(o.work, ignored);  // the clean runs and the scratch folder too
  }
  if (g_stop != 0) {
    std::cout << "interrupted: the trial under way was stopped and cleaned up" << std::endl;
    return 130;
  }
  return violated == 0 ? 0 : 1;
}
