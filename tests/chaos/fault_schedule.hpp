#pragma once
// What one chaos trial does, drawn from its seed alone: the scenario, the run's options and one
// to three faults with the moments they strike. The same seed always gives the same trial, so
// a trial that broke an invariant replays from the seed it printed (tests/chaos/README.md).
//
//   const Trial trial = drawTrial(0x2a);
//   std::cout << describe(trial);   // "default, 6 episodes at x2, --on-sensor-failure stop, ..."
//
// A fault's moment is relative to the run's progress, not to the wall clock of the launch
// alone: "0.4 s into episode 3" waits for episode 3's announced start (the coordinator's
// journal), so that a loaded machine that starts slowly still gets the fault where it was meant.

#include <cstdint>
#include <string>
#include <vector>

namespace sensornet::chaos {

// The processes of a run, as the launcher starts them, and (network trials) a sensor host's
// link.
enum class Target { Launcher, Coordinator, FusionCenter, SensorAgent, SensorHost };

enum class Action {
  Stop,       // SIGSTOP, then SIGCONT after length_s
  Kill,       // SIGKILL
  Interrupt,  // SIGINT (the launcher only)
  Terminate,  // SIGTERM (the launcher only)
  // Network faults (Target::SensorHost), each healed after length_s:
  CutLink,       // the host's link down: nothing in or out
  FusionDeaf,    // the fusion center's host drops what the sensor host sends; the coordinator
                 // still hears it, and it hears both
  HostDeaf,      // the sensor host drops what the coordinator's host sends; the fusion center
                 // still hears it
  LossBurst,     // a fraction `loss` of the packets into and out of the host dropped at random
  ReorderBurst,  // the host's outgoing packets reordered (netem where the kernel has it, else
                 // 30% of them through a slow HTB class)
  // Clock faults (Target::SensorHost): the wall clock of the host's processes (libfaketime;
  // their monotonic clock is left alone, as NTP leaves it), by clock_s seconds:
  ClockOffset,  // off from the start
  ClockStep,    // stepped at the fault's moment (NTP stepping it, a VM resumed)
};

[[nodiscard]] bool isClockFault(Action action);

[[nodiscard]] bool isNetworkFault(Action action);

// Where a fault's moment is counted from.
enum class Anchor {
  Launch,        // the launcher's start: "in the first half second"
  EpisodeStart,  // the announced start of `episode`
};

struct PlannedFault {
  Action action = Action::Stop;
  Target target = Target::SensorAgent;
  int agent = 0;  // SensorAgent: which sensor agent (its first sensor)
  int host = 0;   // SensorHost: which sensor host (0: the first half of the sensors, 1: the rest)
  Anchor anchor = Anchor::EpisodeStart;
  int episode = 0;
  double offset_s = 0.0;  // wall seconds after the anchor
  double length_s = 0.0;  // Stop and network faults: wall seconds until healed
  double loss = 0.0;      // LossBurst: the probability of each packet's drop
  double clock_s = 0.0;   // ClockOffset, ClockStep: how far ahead (> 0) or behind (< 0)
};

enum class ScenarioKind { Default, Lossy, Small };

struct Trial {
  std::uint64_t seed = 0;
  ScenarioKind scenario = ScenarioKind::Default;
  std::uint64_t small_scenario_seed = 1;  // Small: the random plant's seed
  int sensors = 6;                        // of the scenario (one sensor agent each)
  double horizon_s = 3.0;
  int episodes = 6;
  double time_scale = 2.0;
  std::string policy = "replan";  // --on-sensor-failure
  std::uint64_t run_seed = 1;     // --seed of the launch
  // A network trial: the run spans four namespace hosts (coordinator, fusion center, and two
  // sensor hosts with half of the sensors each), and some of its faults strike their links.
  bool on_hosts = false;
  std::vector<PlannedFault> faults;

  [[nodiscard]] double episodeWallS() const { return horizon_s / time_scale; }
};

// `network`: whether the seed may draw a network trial. Without, a seed gives the trial it gave
// before network faults existed (the seeds tests/chaos/README.md names from then replay so).
[[nodiscard]] Trial drawTrial(std::uint64_t seed, bool network = true);

[[nodiscard]] const char* nameOf(Target target);
[[nodiscard]] const char* nameOf(Action action);
[[nodiscard]] const char* nameOf(ScenarioKind kind);

// The sensor host (0 or 1) that runs sensor `agent` in a network trial.
[[nodiscard]] int hostOf(const Trial& trial, int agent);

// "kill fusion_center 0.42 s into episode 3", "stop sensor_agent-2 for 3.1 s 0.2 s after launch",
// "cut edge-1's link for 4.2 s 0.30 s into episode 2"
[[nodiscard]] std::string describe(const PlannedFault& fault);
// The run's options and every fault, on one line.
[[nodiscard]] std::string describe(const Trial& trial);

// The scenario file's text for ScenarioKind::Small (a random plant of the paper's protocol).
[[nodiscard]] std::string smallScenarioYaml(const Trial& trial);

}  // namespace sensornet::chaos
