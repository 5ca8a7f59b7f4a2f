#include "fault_schedule.hpp"

#include <cstdio>

namespace sensornet::chaos {
namespace {

// SplitMix64: a fixed, portable stream, so a seed means the same trial on every standard
// library (std::uniform_*_distribution are not specified bit for bit).
class Stream {
 public:
  explicit Stream(std::uint64_t seed) : state_(seed) {}
  std::uint64_t next() {
    std::uint64_t z = (state_ += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  }
  double uniform(double lo, double hi) {
    return lo + (hi - lo) * static_cast<double>(next() >> 11) * 0x1.0p-53;
  }
  int between(int lo, int hi) {  // inclusive
    return lo + static_cast<int>(next() % static_cast<std::uint64_t>(hi - lo + 1));
  }
  // An index drawn with the given weights (percent, or any positive numbers).
  template <std::size_t N>
  std::size_t weighted(const int (&weights)[N]) {
    int total = 0;
    for (const int w : weights) total += w;
    int pick = between(0, total - 1);
    for (std::size_t i = 0; i < N; ++i) {
      if (pick < weights[i]) return i;
      pick -= weights[i];
    }
    return N - 1;
  }

 private:
  std::uint64_t state_;
};

void drawMoment(Stream& s, const Trial& t, PlannedFault& f);

PlannedFault drawFault(Stream& s, const Trial& t) {
  PlannedFault f;
  // stop any process; kill a sensor agent, the fusion center, the coordinator; signal the
  // launcher (SIGINT, SIGTERM, SIGKILL)
  static constexpr int kKinds[] = {34, 20, 12, 12, 8, 6, 8};
  switch (s.weighted(kKinds)) {
    case 0: {
      f.action = Action::Stop;
      static constexpr int kWho[] = {15, 15, 25, 45};
      f.target = static_cast<Target>(s.weighted(kWho));
      f.length_s = s.uniform(0.5, 12.0);
      break;
    }
    case 1: f.action = Action::Kill; f.target = Target::SensorAgent; break;
    case 2: f.action = Action::Kill; f.target = Target::FusionCenter; break;
    case 3: f.action = Action::Kill; f.target = Target::Coordinator; break;
    case 4: f.action = Action::Interrupt; f.target = Target::Launcher; break;
    case 5: f.action = Action::Terminate; f.target = Target::Launcher; break;
    default: f.action = Action::Kill; f.target = Target::Launcher; break;
  }
  f.agent = s.between(0, t.sensors - 1);
  drawMoment(s, t, f);
  return f;
}

// A fault of a sensor host's link: cut, half deaf either way, lossy or reordering. Cuts and
// partitions last 0.5-15 s, across the stall limits (10 s absorbed, 12 s); bursts 1-8 s.
PlannedFault drawNetworkFault(Stream& s, const Trial& t) {
  PlannedFault f;
  f.target = Target::SensorHost;
  static constexpr int kKinds[] = {30, 20, 15, 20, 15};
  static constexpr Action kActions[] = {Action::CutLink, Action::FusionDeaf, Action::HostDeaf,
                                        Action::LossBurst, Action::ReorderBurst};
  f.action = kActions[s.weighted(kKinds)];
  f.host = s.between(0, 1);
  const bool burst = f.action == Action::LossBurst || f.action == Action::ReorderBurst;
  f.length_s = burst ? s.uniform(1.0, 8.0) : s.uniform(0.5, 15.0);
  if (f.action == Action::LossBurst) f.loss = s.uniform(0.1, 0.5);
  drawMoment(s, t, f);
  return f;
}

}  // namespace

bool isClockFault(Action action) { return action == Action::ClockOffset || action == Action::ClockStep; }

bool isNetworkFault(Action action) {
  return action == Action::CutLink || action == Action::FusionDeaf || action == Action::HostDeaf ||
         action == Action::LossBurst || action == Action::ReorderBurst;
}

int hostOf(const Trial& t, int agent) { return agent < t.sensors / 2 ? 0 : 1; }

namespace {

void drawMoment(Stream& s, const Trial& t, PlannedFault& f) {
  // When: in the target's first half second, in the last episode, or anywhere in between.
  static constexpr int kWhen[] = {20, 25, 55};
  switch (s.weighted(kWhen)) {
    case 0:
      f.anchor = Anchor::Launch;
      f.offset_s = s.uniform(0.0, 0.5);
      break;
    case 1:
      f.episode = t.episodes - 1;
      f.offset_s = s.uniform(0.0, t.episodeWallS());
      break;
    default:
      f.episode = s.between(0, t.episodes - 1);
      f.offset_s = s.uniform(0.0, t.episodeWallS());
      break;
  }
}

}  // namespace

Trial drawTrial(std::uint64_t seed, bool network) {
  Stream s(seed);
  Trial t;
  t.seed = seed;
  static constexpr int kScenarios[] = {45, 35, 20};
  t.scenario = static_cast<ScenarioKind>(s.weighted(kScenarios));
  if (t.scenario == ScenarioKind::Small) {
    t.small_scenario_seed = static_cast<std::uint64_t>(s.between(1, 3));
    t.sensors = 4;
    t.horizon_s = 2.0;
  }
  t.episodes = s.between(4, 9);
  static constexpr double kScales[] = {1.5, 2.0, 3.0};
  t.time_scale = kScales[s.between(0, 2)];
  static constexpr int kPolicies[] = {30, 45, 25};
  static constexpr const char* kPolicyNames[] = {"continue", "replan", "stop"};
  t.policy = kPolicyNames[s.weighted(kPolicies)];
  // Few run seeds, so that the clean runs the costs are compared with are reused.
  t.run_seed = static_cast<std::uint64_t>(s.between(1, 3));
  static constexpr int kCounts[] = {45, 35, 20};
  const std::size_t count = 1 + s.weighted(kCounts);
  for (std::size_t i = 0; i < count; ++i) t.faults.push_back(drawFault(s, t));
  // Network trials from a stream of their own, so that the process faults a seed drew before
  // network faults existed stay what they were. A third of them strike the network alone.
  Stream net(seed ^ 0x6e6574776f726bULL);
  if (network && net.between(0, 99) < 40) {
    t.on_hosts = true;
    if (net.between(0, 2) == 0) t.faults.clear();
    static constexpr int kNetworkCounts[] = {65, 35};
    const std::size_t links = 1 + net.weighted(kNetworkCounts);
    for (std::size_t i = 0; i < links; ++i) t.faults.push_back(drawNetworkFault(net, t));
    // A third of the network trials also put a sensor host's clock off: from the start, or
    // stepped mid-run; ahead twice as often as behind (a clock ahead is what the run detects).
    Stream clock(seed ^ 0x636c6f636bULL);
    if (clock.between(0, 2) == 0) {
      PlannedFault f;
      f.target = Target::SensorHost;
      f.action = clock.between(0, 1) == 0 ? Action::ClockOffset : Action::ClockStep;
      f.host = clock.between(0, 1);
      f.clock_s = clock.uniform(0.2, 3.0) * (clock.between(0, 2) == 0 ? -1.0 : 1.0);
      drawMoment(clock, t, f);
      if (f.action == Action::ClockOffset) {
        f.anchor = Anchor::Launch;
        f.offset_s = 0.0;
      }
      t.faults.push_back(f);
    }
  }
  return t;
}

const char* nameOf(Target target) {
  switch (target) {
    case Target::Launcher: return "launcher";
    case Target::Coordinator: return "coordinator";
    case Target::FusionCenter: return "fusion_center";
    case Target::SensorAgent: return "sensor_agent";
    case Target::SensorHost: return "sensor host";
  }
  return "?";
}

const char* nameOf(Action action) {
  switch (action) {
    case Action::Stop: return "stop";
    case Action::Kill: return "kill -9";
    case Action::Interrupt: return "SIGINT";
    case Action::Terminate: return "SIGTERM";
    case Action::CutLink: return "cut";
    case Action::FusionDeaf: return "fusion center deaf";
    case Action::HostDeaf: return "host deaf";
    case Action::LossBurst: return "loss";
    case Action::ReorderBurst: return "reorder";
    case Action::ClockOffset: return "clock off";
    case Action::ClockStep: return "clock step";
  }
  return "?";
}

const char* nameOf(ScenarioKind kind) {
  switch (kind) {
    case ScenarioKind::Default: return "default";
    case ScenarioKind::Lossy: return "lossy";
    case ScenarioKind::Small: return "small";
  }
  return "?";
}

std::string describe(const PlannedFault& f) {
  char text[200];
  std::string what = nameOf(f.action);
  std::string who = f.target == Target::SensorAgent
                        ? std::string("sensor_agent-") + std::to_string(f.agent)
                        : std::string(nameOf(f.target));
  if (f.target == Target::SensorHost) {
    const std::string host = "edge-" + std::to_string(f.host + 1);
    char clock[32];
    std::snprintf(clock, sizeof clock, "%+.2f s", f.clock_s);
    what = isClockFault(f.action)      ? std::string(f.action == Action::ClockOffset ? "set" : "step")
           : f.action == Action::LossBurst ? "drop " + std::to_string(static_cast<int>(f.loss * 100 + 0.5)) + "% on"
           : f.action == Action::ReorderBurst ? "reorder"
           : f.action == Action::CutLink      ? "cut"
           : f.action == Action::FusionDeaf   ? "deafen the fusion center to"
                                              : "deafen";
    who = isClockFault(f.action)         ? host + "'s clock " + clock
          : f.action == Action::FusionDeaf ? host
          : f.action == Action::HostDeaf ? host + " to the coordinator"
                                         : host + "'s link";
  }
  if (f.action == Action::ClockOffset) return what + " " + who + " from the start";
  const std::string length = f.action == Action::Stop || isNetworkFault(f.action)
                                 ? " for " + std::to_string(f.length_s).substr(0, 4) + " s"
                                 : "";
  if (f.anchor == Anchor::Launch) {
    std::snprintf(text, sizeof text, "%s %s%s %.2f s after it started", what.c_str(),
                  who.c_str(), length.c_str(), f.offset_s);
  } else {
    std::snprintf(text, sizeof text, "%s %s%s %.2f s into episode %d", what.c_str(),
                  who.c_str(), length.c_str(), f.offset_s, f.episode);
  }
  return text;
}

std::string describe(const Trial& t) {
  char head[160];
  std::snprintf(head, sizeof head, "%s%s, %d episodes at x%g, --on-sensor-failure %s, --seed %llu",
                nameOf(t.scenario),
                t.scenario == ScenarioKind::Small
                    ? ("(" + std::to_string(t.small_scenario_seed) + ")").c_str()
                    : "",
                t.episodes, t.time_scale, t.policy.c_str(),
                static_cast<unsigned long long>(t.run_seed));
  std::string line = head;
  line += t.on_hosts ? " on 4 hosts: " : ": ";
  for (std::size_t i = 0; i < t.faults.size(); ++i) {
    line += (i == 0 ? "" : "; ") + describe(t.faults[i]);
  }
  return line;
}

std::string smallScenarioYaml(const Trial& t) {
  return "name: chaos-small\nhorizon: " + std::to_string(t.horizon_s) +
         "\nintervals: 20\nrandom: {states: 3, sensors: " + std::to_string(t.sensors) +
         ", rows_per_sensor: 1, seed: " + std::to_string(t.small_scenario_seed) +
         ", budget: 6, noise_scale: 1}\n";
}

}  // namespace sensornet::chaos
