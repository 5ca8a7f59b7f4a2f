#include "serve_command.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <thread>

#include "sensornet/core/emulated_plant.hpp"
#include "sensornet/core/input_error.hpp"
#include "sensornet/core/planner.hpp"
#include "sensornet/core/surrogate.hpp"
#include "sensornet/dds/participant.hpp"
#include "sensornet/dds/reader.hpp"
#include "sensornet/dds/topics.hpp"
#include "sensornet/dds/waitset.hpp"
#include "sensornet/dds/wire.hpp"
#include "sensornet/dds/writer.hpp"
#include "sensornet/emulator/messages.hpp"
#include "sensornet/emulator/run_inputs.hpp"
#include "sensornet/emulator/run_options.hpp"
#include "sensornet/emulator/stall_watch.hpp"
#include "sensornet/emulator/stop_signal.hpp"
#include "sensornet/io/scenario_file.hpp"

namespace sensornet::coordinator {
namespace {

using namespace std::chrono_literals;
using emulator::wallNowNs;

struct ServeOptions {
  emulator::RunOptions run;
  std::string scenario_path;
  PlanSurrogate surrogate = PlanSurrogate::Information;
  std::string schedule_path;
  int episodes = 20;
  double time_scale = 1.0;
  std::uint64_t seed = 1;
  double ready_timeout_s = 30.0;
  double start_lead_s = 0.2;     // wall seconds between announcing an episode and its start
  double switch_margin_s = 0.3;  // wall seconds between a re-plan and its effective time
  double report_timeout_s = 30.0;  // wall seconds of fusion-center silence before giving up
  bool json = false;
};

std::int64_t toNs(double seconds) { return static_cast<std::int64_t>(1e9 * seconds); }

class Coordinator {
 public:
  Coordinator(const ServeOptions& options, emulator::RunScenario run,
              emulator::ScheduleVersion initial)
      : options_(options),
        run_(std::move(run)),
        plant_(run_.scenario, run_.seed),
        constraints_(run_.scenario.constraints),
        surrogate_(initial.surrogate == "file" ? PlanSurrogate::Information : options.surrogate),
        domain_(options.run.domainConfig()),
        participant_(domain_),
        scenario_topic_(participant_),
        schedule_topic_(participant_),
        control_topic_(participant_),
        command_topic_(participant_),
        reply_topic_(participant_),
        status_topic_(participant_),
        report_topic_(participant_),
        state_topic_(participant_),
        scenario_writer_(participant_, scenario_topic_),
        schedule_writer_(participant_, schedule_topic_),
        control_writer_(participant_, control_topic_),
        reply_writer_(participant_, reply_topic_),
        command_reader_(participant_, command_topic_),
        status_reader_(participant_, status_topic_),
        report_reader_(participant_, report_topic_),
        state_reader_(participant_, state_topic_),
        waitset_(participant_),
        command_ready_(command_reader_),
        status_ready_(status_reader_),
        report_ready_(report_reader_) {
    waitset_.attach(command_ready_, 1);
    waitset_.attach(status_ready_, 2);
    waitset_.attach(report_ready_, 3);
    book_.add(std::move(initial));
  }

  int run() {
    mustWrite(emulator::publishScenario(scenario_writer_, options_.run.run_id, run_), "scenario");
    mustWrite(emulator::publishSchedule(schedule_writer_, options_.run.run_id, run_.digest,
                                        book_.latest()),
              "schedule");
    spdlog::info("run {}: scenario {} and schedule v1 ({}) published; waiting for {} sensors "
                 "and the fusion center",
                 options_.run.run_id, run_.digest, book_.latest().surrogate,
                 run_.scenario.sensorCount());
    if (!waitUntilReady()) return kExitFailure;

    for (std::uint32_t e = 0; e < static_cast<std::uint32_t>(options_.episodes) && !stopping_;
         ++e) {
      if (!runEpisode(e)) {
        shutDown(emulator::stopRequested() ? "the coordinator was stopped by a signal"
                                           : "no report of episode " + std::to_string(e));
        return kExitFailure;
      }
    }
    shutDown("");
    if (emulator::stopRequested()) return kExitFailure;
    if (options_.json) {
      printJson({{"run_id", options_.run.run_id},
                 {"episodes", episodes_done_},
                 {"schedule_versions", book_.latest().version}});
    }
    return kExitOk;
  }

 private:
  static void mustWrite(dds::WriteResult result, const char* what) {
    if (result == dds::WriteResult::TimedOut) {
      throw std::runtime_error(std::string("publishing the ") + what + " timed out");
    }
  }

  bool waitUntilReady() {
    const std::int64_t deadline = wallNowNs() + toNs(options_.ready_timeout_s);
    for (;;) {
      pump(20ms);
      const bool sensors_ready = static_cast<int>(ready_sensors_.size()) ==
                                 run_.scenario.sensorCount();
      const bool fusion_ready = report_reader_.matchedWriters() > 0 &&
                                state_reader_.matchedWriters() > 0;
      if (sensors_ready && fusion_ready) {
        spdlog::info("all {} sensors and the fusion center are ready", ready_sensors_.size());
        std::this_thread::sleep_for(100ms);  // let the last discovery settle
        return true;
      }
      if (emulator::stopRequested()) return false;
      if (wallNowNs() > deadline) {
        spdlog::error("not ready after {} s: {} of {} sensors ready, fusion center {}",
                      options_.ready_timeout_s, ready_sensors_.size(),
                      run_.scenario.sensorCount(), fusion_ready ? "present" : "missing");
        return false;
      }
    }
  }

  bool runEpisode(std::uint32_t episode) {
    current_episode_ = episode;
    clock_ = {wallNowNs() + toNs(options_.start_lead_s), options_.time_scale};
    const emulator::ScheduleVersion* v = book_.inForce(episode, 0.0);
    sensornet_EpisodeControl c{};
    c.run_id = dds::borrowString(options_.run.run_id);
    c.episode = episode;
    c.command = sensornet_EPISODE_START;
    c.start_wall_time_ns = clock_.start_wall_ns;
    c.time_scale = options_.time_scale;
    c.seed = run_.seed;
    c.schedule_version = v->version;
    c.episodes_planned = static_cast<std::uint32_t>(options_.episodes);
    mustWrite(control_writer_.write(c), "episode control");
    running_ = true;
    // The fusion center closes the episode once every sensor's count is in, which after a
    // stall can take a while; it publishes its state meanwhile. Give up only when it has shown
    // no sign of life for report_timeout_s after the episode's end, not counting the time this
    // process was stalled itself.
    const std::int64_t end_ns = clock_.wallAt(run_.scenario.horizon_s);
    fusion_heard_ns_ = end_ns;
    while (!reported_.count(episode)) {
      pump(10ms);
      if (emulator::stopRequested()) return false;
      const std::int64_t now = wallNowNs();
      const std::int64_t from = std::max(end_ns, fusion_heard_ns_);
      if (now > from && 1e-9 * static_cast<double>(now - from) -
                                stall_watch_.stalledBetween(from, now) >
                            options_.report_timeout_s) {
        spdlog::error("no report of episode {} and no sign of the fusion center for {} s",
                      episode, options_.report_timeout_s);
        return false;
      }
    }
    running_ = false;
    ++episodes_done_;
    return true;
  }

  // Ends the run; `failure` empty when every episode ran.
  void shutDown(const std::string& failure) {
    sensornet_EpisodeControl c{};
    c.run_id = dds::borrowString(options_.run.run_id);
    c.episode = current_episode_;
    c.command = sensornet_RUN_SHUTDOWN;
    c.start_wall_time_ns = wallNowNs();
    c.time_scale = options_.time_scale;
    c.seed = run_.seed;
    c.schedule_version = book_.latest().version;
    c.episodes_planned = static_cast<std::uint32_t>(episodes_done_);
    c.aborted = !failure.empty();
    c.detail = dds::borrowString(failure);
    if (control_writer_.write(c) == dds::WriteResult::TimedOut) {
      spdlog::warn("the shutdown announcement timed out");
    }
    (void)control_writer_.waitForAcks(3s);
    (void)reply_writer_.waitForAcks(1s);
    spdlog::info("run {} shut down after {} episodes", options_.run.run_id, episodes_done_);
  }

  // Waits up to `timeout` for something to read, then reads everything.
  void pump(std::chrono::nanoseconds timeout) {
    (void)waitset_.wait(timeout);
    if (const auto stall = stall_watch_.tick(wallNowNs())) {
      spdlog::warn("the coordinator was stalled for {:.3g} s", stall->seconds());
    }
    readStatuses();
    readReports();
    readFusionStates();
    readCommands();
    stall_watch_.busyUntil(wallNowNs());  // planning a live change is work, not a stall
  }

  void readStatuses() {
    for (auto& received : status_reader_.take(64).samples) {
      const sensornet_SensorStatus& s = *received.sample;
      const int id = static_cast<int>(s.sensor_id);
      if (id < 0 || id >= run_.scenario.sensorCount()) continue;
      if (s.state == sensornet_SENSOR_READY || s.state == sensornet_SENSOR_EXCLUDED ||
          s.state == sensornet_SENSOR_RUNNING) {
        if (s.schedule_version >= 1) ready_sensors_.insert(id);
      }
      if (s.state == sensornet_SENSOR_FAILED) {
        spdlog::warn("sensor {} failed: {}", id, dds::viewString(s.detail));
      }
    }
  }

  void readReports() {
    for (auto& received : report_reader_.take(16).samples) {
      const sensornet_Report& r = *received.sample;
      fusion_heard_ns_ = std::max(fusion_heard_ns_, wallNowNs());
      if (!reported_.insert(r.episode).second) continue;
      spdlog::info("[{}/{}] episode {}: realized {:.6g}, bracket [{:.6g}, {:.6g}]; mean {:.6g} "
                   "in [{:.6g}, {:.6g}] (95%)",
                   r.summary.episodes, options_.episodes, r.episode, r.realized_cost,
                   r.bracket_lower, r.bracket_upper, r.summary.realized_mean,
                   r.summary.realized_ci95_low, r.summary.realized_ci95_high);
    }
  }

  void readFusionStates() {
    for (auto& received : state_reader_.take(8).samples) {
      const sensornet_FusionState& s = *received.sample;
      const auto values = dds::viewSequence(s.covariance);
      const auto n = static_cast<std::size_t>(run_.scenario.stateDim());
      if (s.state_dim != n || values.size() != n * n) continue;
      Eigen::MatrixXd P = Eigen::Map<const Eigen::MatrixXd>(values.data(),
                                                            static_cast<Eigen::Index>(n),
                                                            static_cast<Eigen::Index>(n));
      fused_ = FusedEstimate{s.episode, s.emulated_time_s, 0.5 * (P + P.transpose())};
      fusion_heard_ns_ = std::max(fusion_heard_ns_, wallNowNs());
    }
  }

  void readCommands() {
    for (auto& received : command_reader_.take(8).samples) {
      const sensornet_Command& c = *received.sample;
      if (dds::viewString(c.run_id) != options_.run.run_id) continue;
      std::uint32_t version = 0;
      std::string reason;
      bool accepted = false;
      try {
        std::tie(version, reason) = execute(c);
        accepted = true;
      } catch (const InputError& error) {
        reason = error.what();
      } catch (const std::exception& error) {
        reason = std::string("failed: ") + error.what();
      }
      spdlog::info("command {} from '{}': {} ({})", c.command_id, dds::viewString(c.issuer),
                   accepted ? "accepted" : "refused", reason);
      sensornet_CommandReply reply{};
      reply.run_id = dds::borrowString(options_.run.run_id);
      reply.command_id = c.command_id;
      reply.accepted = accepted;
      reply.schedule_version = version;
      reply.reason = dds::borrowString(reason);
      if (reply_writer_.write(reply) == dds::WriteResult::TimedOut) {
        spdlog::warn("the reply to command {} timed out", c.command_id);
      }
    }
  }

  // Returns (new version or 0, one-line summary); throws InputError to refuse. A change of
  // settings (surrogate, excluded sensors, budget) holds only once its plans are published: a
  // refused or failed re-plan leaves them as they were.
  std::pair<std::uint32_t, std::string> execute(const sensornet_Command& c) {
    const std::string source = "command " + std::to_string(c.command_id);
    const auto replanWith = [&](PlanSurrogate surrogate, std::set<int> excluded,
                                ResourceConstraints constraints) {
      const PlanSurrogate kept_surrogate = surrogate_;
      std::set<int> kept_excluded = excluded_;
      ResourceConstraints kept_constraints = constraints_;
      surrogate_ = surrogate;
      excluded_ = std::move(excluded);
      constraints_ = std::move(constraints);
      try {
        return replan(c.command_id, std::nullopt);
      } catch (...) {
        surrogate_ = kept_surrogate;
        excluded_ = std::move(kept_excluded);
        constraints_ = std::move(kept_constraints);
        throw;
      }
    };
    switch (c.kind) {
      case sensornet_COMMAND_STATUS:
        return {0, "running episode " + std::to_string(current_episode_) + ", schedule v" +
                       std::to_string(book_.latest().version)};
      case sensornet_COMMAND_SENSORS_FAILED:
        throw InputError(source, "kind", "a command kind this coordinator handles");
      case sensornet_COMMAND_SHUTDOWN:
        stopping_ = true;
        return {0, "the run ends after the current episode"};
      case sensornet_COMMAND_REPLAN: {
        const std::string s(dds::viewString(c.surrogate));
        PlanSurrogate surrogate = PlanSurrogate::Uniform;
        if (s == "info") {
          surrogate = PlanSurrogate::Information;
        } else if (s == "cov") {
          surrogate = PlanSurrogate::Covariance;
        } else if (s != "uniform") {
          throw InputError(source, "surrogate", "info, cov or uniform, got '" + s + "'");
        }
        return replanWith(surrogate, excluded_, constraints_);
      }
      case sensornet_COMMAND_EXCLUDE_SENSORS: {
        std::set<int> excluded = excluded_;
        for (const std::uint32_t id : dds::viewSequence(c.sensor_ids)) {
          if (id >= static_cast<std::uint32_t>(run_.scenario.sensorCount())) {
            throw InputError(source, "sensor_ids",
                             "ids below M = " + std::to_string(run_.scenario.sensorCount()));
          }
          excluded.insert(static_cast<int>(id));
        }
        if (static_cast<int>(excluded.size()) == run_.scenario.sensorCount()) {
          throw InputError(source, "sensor_ids", "at least one sensor left in service");
        }
        return replanWith(surrogate_, std::move(excluded), constraints_);
      }
      case sensornet_COMMAND_SET_BUDGET: {
        const auto b = dds::viewSequence(c.budget);
        if (b.size() != static_cast<std::size_t>(constraints_.b.size())) {
          throw InputError(source, "budget",
                           std::to_string(constraints_.b.size()) + " values (one per row of C)");
        }
        for (const double value : b) {
          if (!(value > 0.0) || !std::isfinite(value)) {
            throw InputError(source, "budget", "finite values > 0, got " + formatNumber(value));
          }
        }
        ResourceConstraints constraints = constraints_;
        constraints.b = Eigen::Map<const Eigen::VectorXd>(b.data(), constraints_.b.size());
        // The rules of a scenario file hold for a live budget too (at most
        // kMaxMeasurementsPerHorizon expected measurements per sensor and horizon, ...).
        Scenario check = run_.scenario;
        check.constraints = constraints;
        try {
          validateScenario(check, source);
        } catch (const InputError& e) {
          throw InputError(source, "budget", e.expected());
        }
        return replanWith(surrogate_, excluded_, std::move(constraints));
      }
      case sensornet_COMMAND_SCHEDULE_FILE: {
        RateSchedule schedule =
            parseScheduleJson(std::string(dds::viewString(c.schedule_json)), source);
        Scenario check = run_.scenario;
        check.constraints = constraints_;
        const Feasibility feasibility = checkFeasibility(schedule, check, 1e-9);
        if (!feasibility.feasible) throw InputError(source, "rates", feasibility.reason);
        return replan(c.command_id, std::move(schedule));
      }
    }
    throw InputError(source, "kind", "a known command kind");
  }

  // Plans (or adopts `given`) and publishes the next version, effective as soon as every
  // process can switch: switch_margin_s of wall time from now in the running episode (planned
  // over the rest of the horizon from the fused covariance; later if planning overran, so that
  // half a margin is always left for the version to reach everyone), else at the start of the
  // next episode. A mid-episode change publishes a second version for the episodes after it,
  // planned over the whole horizon from P0 with the same settings.
  //
  // Both plans are made, and both must be ones the planner reports as optimal ("acceptable"
  // is taken and named in the summary; "not_optimized" is the uniform schedule), before either
  // is published: otherwise this throws InputError and nothing is published. A projected
  // quasi-Newton solve that "stalled" (no step decreases the cost in floating point) at a point
  // whose scale-free KKT residual is at most kStationaryResidual (every planned rate within
  // 0.1% of its projected-gradient step) is taken too, and named so in the reply: the fused
  // covariance a mid-episode plan starts from often leaves the cost too flat for the 1e-6
  // tolerance.
  static constexpr double kStationaryResidual = 1e-3;
  static bool stalledAtAStationaryPoint(const PlanResult& plan) {
    return plan.status == "stalled" && plan.kkt_residual <= kStationaryResidual;
  }

  std::pair<std::uint32_t, std::string> replan(std::uint64_t command_id,
                                               std::optional<RateSchedule> given) {
    Scenario planned_for = run_.scenario;
    planned_for.constraints = constraints_;
    const std::uint32_t next_episode = running_ || episodes_done_ > 0 ? current_episode_ + 1 : 0;
    const std::string surrogate(describe(surrogate_));

    if (given) {
      emulator::ScheduleVersion v =
          makeVersion(planned_for, std::move(*given), "file", command_id, next_episode, 0.0);
      return {publish(std::move(v)), "schedule file"};
    }
    const auto requireOptimal = [&](const PlanResult& plan, const std::string& which) {
      if (plan.status == "optimal" || plan.status == "acceptable" ||
          plan.status == "not_optimized" || stalledAtAStationaryPoint(plan)) {
        return;
      }
      throw InputError("command " + std::to_string(command_id), "plan",
                       "a plan the planner reports as optimal, but the " + which + " " + surrogate +
                           " plan ended '" + plan.status + "' (kkt residual " +
                           formatNumber(plan.kkt_residual) + " after " +
                           std::to_string(plan.iterations) +
                           " iterations); nothing was published, the settings are unchanged");
    };
    const auto describePlan = [](const PlanResult& plan) {
      if (plan.status == "acceptable") return std::string("acceptable: IPOPT's looser tolerance");
      if (stalledAtAStationaryPoint(plan)) {
        return "stalled, accepted: kkt residual " + formatNumber(plan.kkt_residual) + " <= " +
               formatNumber(kStationaryResidual);
      }
      return plan.status;
    };
    // Mid-episode: the rest of this episode, from the latest fused covariance.
    std::string summary;
    const auto notInThisEpisode = [this](const char* why) {
      return "not in episode " + std::to_string(current_episode_) + ": " + why + "; ";
    };
    std::optional<PlanResult> tail_plan;
    double at = 0.0;
    const double margin = options_.switch_margin_s * options_.time_scale;
    if (running_ && !(fused_ && fused_->episode == current_episode_)) {
      summary = notInThisEpisode("no fused covariance of it yet");
    } else if (running_) {
      at = plant_.timeOf(plant_.tickAt(emulatedNow() + margin));
      if (at >= run_.scenario.horizon_s) {
        summary = notInThisEpisode("it ends within the switch margin");
      } else {
        PlanRequest request = planRequest();
        request.start_time = at;
        request.start_covariance = covarianceExpectedAt(at);
        tail_plan = planSchedule(planned_for, request);
        requireOptimal(*tail_plan, "mid-episode");
      }
    }
    const PlanResult plan = planSchedule(planned_for, planRequest());
    requireOptimal(plan, "full-horizon");
    std::optional<emulator::ScheduleVersion> tail;
    if (tail_plan) {
      tail = makeVersion(planned_for, tail_plan->schedule, surrogate, command_id, current_episode_,
                         at);
    }
    emulator::ScheduleVersion full =
        makeVersion(planned_for, plan.schedule, surrogate, command_id, next_episode, 0.0);

    // Planning took time. Every process must still hear of the version before it takes
    // effect: if less than half the margin is left, it takes effect later, at the first tick
    // half a margin from now (the plan's rates from there on; they stay feasible).
    std::uint32_t first_version = 0;
    if (tail) {
      const double earliest = plant_.timeOf(plant_.tickAt(emulatedNow() + 0.5 * margin) + 1);
      tail->effective_time_s = std::max(at, earliest);
      if (tail->effective_time_s < run_.scenario.horizon_s) {
        const double effective = tail->effective_time_s;
        first_version = publish(std::move(*tail));
        summary = "version " + std::to_string(first_version) + " from " +
                  std::to_string(effective) + " s of episode " + std::to_string(current_episode_) +
                  " (" + describePlan(*tail_plan) + ", planned from the fused covariance at " +
                  std::to_string(fused_->time_s) + " s carried to " + std::to_string(at) + " s); ";
      } else {
        summary = notInThisEpisode("planning outlasted it");
      }
    }
    full.version = book_.latest().version + 1;  // after the mid-episode version, if any
    const std::uint32_t full_version = publish(std::move(full));
    summary += "version " + std::to_string(full_version) + " from episode " +
               std::to_string(next_episode) + " (" + surrogate + ", " + describePlan(plan) + ")";
    return {first_version != 0 ? first_version : full_version, summary};
  }

  // The latest fused covariance carried forward to `at` (what arrives in between is not fused
  // yet) by the surrogate of the plan's form under the version in force: the plan of the rest
  // of the episode starts from the covariance expected when it takes effect.
  [[nodiscard]] Eigen::MatrixXd covarianceExpectedAt(double at) const {
    const emulator::ScheduleVersion* v = book_.inForce(current_episode_, fused_->time_s);
    if (v == nullptr || !(fused_->time_s < at)) return fused_->covariance;
    RolloutOptions carry;
    carry.start_time = fused_->time_s;
    carry.end_time = at;
    carry.start_covariance = fused_->covariance;
    return rollout(formOf(surrogate_), run_.scenario, v->schedule, carry).covariances.back();
  }

  [[nodiscard]] double emulatedNow() const { return std::max(0.0, clock_.emulatedNow()); }

  [[nodiscard]] PlanRequest planRequest() const {
    PlanRequest request;
    request.surrogate = surrogate_;
    request.excluded_sensors.assign(excluded_.begin(), excluded_.end());
    request.warm_start = book_.latest().schedule;
    request.max_seconds = 30.0;
    return request;
  }

  emulator::ScheduleVersion makeVersion(const Scenario& planned_for, RateSchedule schedule,
                                        std::string surrogate, std::uint64_t command_id,
                                        std::uint32_t episode, double at) const {
    emulator::ScheduleVersion v;
    v.version = book_.latest().version + 1;
    v.effective_episode = episode;
    v.effective_time_s = at;
    v.bracket = computeBracket(planned_for, schedule);
    v.schedule = std::move(schedule);
    v.surrogate = std::move(surrogate);
    v.command_id = command_id;
    return v;
  }

  std::uint32_t publish(emulator::ScheduleVersion v) {
    mustWrite(emulator::publishSchedule(schedule_writer_, options_.run.run_id, run_.digest, v),
              "schedule");
    const std::uint32_t number = v.version;
    book_.add(std::move(v));
    return number;
  }

  struct FusedEstimate {
    std::uint32_t episode = 0;
    double time_s = 0.0;
    Eigen::MatrixXd covariance;
  };

  ServeOptions options_;
  emulator::RunScenario run_;
  EmulatedPlant plant_;  // only for its tick grid: effective times fall on ticks
  ResourceConstraints constraints_;
  PlanSurrogate surrogate_;
  std::set<int> excluded_;
  emulator::ScheduleBook book_;

  dds::Domain domain_;
  dds::Participant participant_;
  dds::Topic<sensornet_Scenario> scenario_topic_;
  dds::Topic<sensornet_Schedule> schedule_topic_;
  dds::Topic<sensornet_EpisodeControl> control_topic_;
  dds::Topic<sensornet_Command> command_topic_;
  dds::Topic<sensornet_CommandReply> reply_topic_;
  dds::Topic<sensornet_SensorStatus> status_topic_;
  dds::Topic<sensornet_Report> report_topic_;
  dds::Topic<sensornet_FusionState> state_topic_;
  dds::Writer<sensornet_Scenario> scenario_writer_;
  dds::Writer<sensornet_Schedule> schedule_writer_;
  dds::Writer<sensornet_EpisodeControl> control_writer_;
  dds::Writer<sensornet_CommandReply> reply_writer_;
  dds::Reader<sensornet_Command> command_reader_;
  dds::Reader<sensornet_SensorStatus> status_reader_;
  dds::Reader<sensornet_Report> report_reader_;
  dds::Reader<sensornet_FusionState> state_reader_;
  dds::WaitSet waitset_;
  dds::ReadCondition command_ready_;
  dds::ReadCondition status_ready_;
  dds::ReadCondition report_ready_;

  std::set<int> ready_sensors_;
  std::set<std::uint32_t> reported_;
  std::int64_t fusion_heard_ns_ = 0;  // the fusion center's latest state or report
  emulator::StallWatch stall_watch_;
  std::optional<FusedEstimate> fused_;
  std::uint32_t current_episode_ = 0;
  emulator::EpisodeClock clock_;  // of the current episode
  bool running_ = false;
  bool stopping_ = false;
  int episodes_done_ = 0;
};

int runServe(const ServeOptions& options) {
  emulator::RunScenario run;
  run.yaml = readTextFile(options.scenario_path, "scenario");  // read once: parsed and sent
  run.scenario = parseScenarioYaml(run.yaml, options.scenario_path);
  run.digest = emulator::digestOf(run.yaml);
  run.seed = options.seed;
  (void)options.run.domainConfig();  // bad run or domain id: exit 2 before any planning

  emulator::ScheduleVersion initial;
  initial.version = 1;
  if (!options.schedule_path.empty()) {
    initial.schedule = loadScheduleFile(options.schedule_path, run.scenario);
    initial.surrogate = "file";
  } else {
    PlanRequest request;
    request.surrogate = options.surrogate;
    const PlanResult plan = planSchedule(run.scenario, request);
    spdlog::info("initial {} schedule: {} after {} iterations in {:.3f} s", describe(options.surrogate),
                 plan.status, plan.iterations, plan.solve_seconds);
    initial.schedule = plan.schedule;
    initial.surrogate = std::string(describe(options.surrogate));
  }
  initial.bracket = computeBracket(run.scenario, initial.schedule);
  spdlog::info("bracket of schedule v1: [{:.6g}, {:.6g}]", initial.bracket.info,
               initial.bracket.cov);
  emulator::installStopSignals();
  Coordinator coordinator(options, std::move(run), std::move(initial));
  return coordinator.run();
}

}  // namespace

Subcommand addServeCommand(CLI::App& app) {
  auto options = std::make_shared<ServeOptions>();
  CLI::App* cmd = app.add_subcommand(
      "serve",
      "Coordinate one emulation run over DDS: publish the scenario and the planned schedule, "
      "wait for every sensor and the fusion center, run the episodes on the emulated clock, "
      "re-plan live on command (sensornet replan), then shut the run down. Example:\n"
      "  coordinator serve --scenario scenarios/default.yaml --run-id demo --episodes 20");
  emulator::addRunOptions(*cmd, options->run);
  cmd->add_option("--scenario", options->scenario_path, "scenario file (YAML)")->required();
  const std::map<std::string, PlanSurrogate> surrogates = {
      {"info", PlanSurrogate::Information},
      {"cov", PlanSurrogate::Covariance},
      {"uniform", PlanSurrogate::Uniform}};
  cmd->add_option("--surrogate", options->surrogate,
                  "how to plan the initial schedule: info, cov or uniform")
      ->transform(CLI::CheckedTransformer(surrogates, CLI::ignore_case))
      ->capture_default_str();
  cmd->add_option("--schedule", options->schedule_path,
                  "use this schedule file (JSON) instead of planning");
  cmd->add_option("--episodes", options->episodes, "episodes to run")
      ->capture_default_str()
      ->check(integerRange(emulator::kMinEpisodes, emulator::kMaxEpisodes));
  cmd->add_option("--time-scale", options->time_scale,
                  "emulated seconds per wall second (1 = real time, 10 = ten times faster)")
      ->capture_default_str()
      ->check(numberRange(emulator::kMinTimeScale, emulator::kMaxTimeScale));
  cmd->add_option("--seed", options->seed,
                  "run seed: keys the plant truth, the arrivals and the sensor noise")
      ->capture_default_str();
  cmd->add_option("--ready-timeout", options->ready_timeout_s,
                  "seconds to wait for every sensor and the fusion center")
      ->capture_default_str()
      ->check(positiveNumber(emulator::kMaxWallSeconds));
  cmd->add_option("--switch-margin", options->switch_margin_s,
                  "wall seconds between a live re-plan and the time it takes effect")
      ->capture_default_str()
      ->check(positiveNumber(emulator::kMaxWallSeconds));
  cmd->add_flag("--json", options->json, "print a one-line JSON summary at the end");
  return {cmd, [options] { return runServe(*options); }};
}

}  // namespace sensornet::coordinator
