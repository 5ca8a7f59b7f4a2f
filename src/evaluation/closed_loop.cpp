#include "sensornet/evaluation/closed_loop.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <exception>
#include <mutex>
#include <string>
#include <thread>
#include <utility>

#include "sensornet/core/cdkf.hpp"
#include "sensornet/core/emulated_plant.hpp"
#include "sensornet/core/input_error.hpp"
#include "sensornet/core/poisson_arrivals.hpp"
#include "sensornet/core/student_t.hpp"
#include "sensornet/core/surrogate.hpp"
#include "sensornet/emulator/schedule_book.hpp"

namespace sensornet::evaluation {

using namespace sensornet::emulator;  // the coordinator's re-planner, as the live run uses it
namespace {

constexpr const char* kSource = "closed loop";

// Runs body(episode, worker) for episodes 0..runs-1 on `threads` workers, each with its own
// state made by make(); progress(done, runs) from the calling thread. The first exception is
// rethrown once every worker has stopped.
template <typename Make, typename Body>
void forEachEpisode(int runs, int threads, const std::function<void(int, int)>& progress,
                    const Make& make, const Body& body) {
  std::atomic<int> next{0};
  std::atomic<int> done{0};
  std::atomic<bool> failed{false};
  std::exception_ptr error;
  std::mutex error_mutex;
  auto work = [&] {
    try {
      auto state = make();
      for (int e = next.fetch_add(1); e < runs && !failed; e = next.fetch_add(1)) {
        body(e, state);
        done.fetch_add(1);
      }
    } catch (...) {
      const std::lock_guard lock(error_mutex);
      if (!error) error = std::current_exception();
      failed = true;
    }
  };
  const int count = std::clamp(threads > 0 ? threads
                                           : static_cast<int>(std::thread::hardware_concurrency()),
                               1, std::max(1, runs));
  {
    std::vector<std::jthread> workers;
    for (int w = 0; w < count; ++w) workers.emplace_back(work);
    int reported = 0;
    while (progress && reported < runs && !failed) {
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
      const int now = done.load();
      if (now != reported) progress(reported = now, runs);
    }
  }
  if (error) std::rethrow_exception(error);
  if (progress) progress(runs, runs);
}

// One worker's filter and buffer: an episode advanced piece by piece under a schedule book.
class EpisodeRunner {
 public:
  explicit EpisodeRunner(const Scenario& scenario) : scenario_(scenario), filter_(scenario) {}

  void start(std::uint64_t seed, std::uint64_t episode) {
    filter_.reset();
    arrivals_.emplace(scenario_.sensorCount(), seed, episode);
    count_ = 0;
  }

  // Draws and fuses the arrivals of [now, to) under the versions of `book` in force there
  // (episode 0 of the book), then propagates to `to`.
  void advance(const ScheduleBook& book, double to) {
    for (const ScheduleSegment& segment : book.segments(0, scenario_.horizon_s)) {
      const double until = std::min(segment.to_s, to);
      if (until <= arrivals_->now()) continue;
      arrivals_->drawUntil(segment.version->schedule, until, buffer_);
      for (const Arrival& a : buffer_) {
        filter_.propagateTo(a.time);
        filter_.updateCovariance(a.sensor);
      }
      count_ += static_cast<long long>(buffer_.size());
      if (until >= to) break;
    }
    filter_.propagateTo(to);
  }

  [[nodiscard]] const CdKalmanFilter& filter() const { return filter_; }
  [[nodiscard]] long long arrivals() const { return count_; }

 private:
  const Scenario& scenario_;
  CdKalmanFilter filter_;
  std::optional<TimeChangedArrivals> arrivals_;
  std::vector<Arrival> buffer_;
  long long count_ = 0;
};

ScheduleVersion openLoopVersion(const Scenario& scenario, const RateSchedule& schedule,
                                PlanSurrogate surrogate) {
  ScheduleVersion v;
  v.version = 1;
  v.schedule = schedule;
  v.surrogate = surrogateKindOf(surrogate);
  v.bracket = computeBracket(scenario, schedule);
  return v;
}

void checkFits(const Scenario& scenario, const RateSchedule& schedule) {
  if (schedule.sensorCount() != scenario.sensorCount() ||
      schedule.intervals() != scenario.intervals ||
      !(std::abs(schedule.horizon() - scenario.horizon_s) <= 1e-12 * scenario.horizon_s)) {
    throw InputError(kSource, "schedule",
                     std::to_string(scenario.intervals) + " intervals x " +
                         std::to_string(scenario.sensorCount()) + " sensors over T = " +
                         std::to_string(scenario.horizon_s));
  }
}

}  // namespace

std::vector<double> replanInstants(double every_s, double horizon_s) {
  if (!(std::isfinite(every_s) && every_s > 0.0)) {
    throw InputError(kSource, "replan_every", "a number of emulated seconds > 0, got " +
                                                  std::to_string(every_s));
  }
  std::vector<double> instants;
  for (int k = 1; k * every_s < horizon_s * (1.0 - 1e-12); ++k) instants.push_back(k * every_s);
  return instants;
}

ClosedLoopResult simulateClosedLoop(const Scenario& scenario, const RateSchedule& open_loop,
                                    const ClosedLoopOptions& options) {
  checkFits(scenario, open_loop);
  if (options.runs < 1) throw InputError(kSource, "runs", "an integer >= 1");
  if (options.threads < 0) throw InputError(kSource, "threads", "an integer >= 0");
  if (options.surrogate != PlanSurrogate::Information &&
      options.surrogate != PlanSurrogate::Covariance) {
    throw InputError(kSource, "surrogate",
                     "info or cov, got " + std::string(wordOf(options.surrogate)));
  }
  const std::vector<double> instants = replanInstants(options.replan_every_s, scenario.horizon_s);
  const EmulatedPlant plant(scenario, options.seed);  // only its tick grid
  const Replanner replanner(scenario, plant, initialSettings(scenario, options.surrogate),
                            options.replanner);
  const ScheduleVersion base = openLoopVersion(scenario, open_loop, options.surrogate);

  ClosedLoopResult result;
  result.runs = options.runs;
  result.episode_costs.assign(static_cast<std::size_t>(options.runs), 0.0);
  std::vector<int> tails(static_cast<std::size_t>(options.runs), 0);
  std::vector<int> refused(static_cast<std::size_t>(options.runs), 0);
  std::vector<long long> arrivals(static_cast<std::size_t>(options.runs), 0);
  forEachEpisode(
      options.runs, options.threads, options.progress,
      [&] { return EpisodeRunner(scenario); },
      [&](int e, EpisodeRunner& runner) {
        const auto i = static_cast<std::size_t>(e);
        ScheduleBook book;
        book.add(base);
        runner.start(options.seed, static_cast<std::uint64_t>(e));
        for (const double t : instants) {
          runner.advance(book, t);
          RunMoment now;
          now.running = true;
          now.episode = 0;
          now.fused = FusedCovariance{0, t, runner.filter().covariance()};
          now.emulated_now = [t] { return t; };
          try {
            const Replan r = replanner.replanTail(book, now, 0);
            if (!r.versions.empty()) ++tails[i];
            for (const ScheduleVersion& v : r.versions) book.add(v);
          } catch (const InputError&) {
            ++refused[i];  // as live: nothing is published, the schedule in force stays
          }
        }
        runner.advance(book, scenario.horizon_s);
        result.episode_costs[i] = runner.filter().cost();
        arrivals[i] = runner.arrivals();
      });
  const SampleMean s = sampleMean(result.episode_costs);
  result.mean = s.mean;
  result.std_dev = s.std_dev;
  result.ci95 = s.ci95;
  long long tail_total = 0, arrival_total = 0;
  for (std::size_t i = 0; i < tails.size(); ++i) {
    tail_total += tails[i];
    result.refused += refused[i];
    arrival_total += arrivals[i];
  }
  result.tails_mean = static_cast<double>(tail_total) / options.runs;
  result.arrivals_mean = static_cast<double>(arrival_total) / options.runs;
  return result;
}

std::vector<double> openLoopCosts(const Scenario& scenario, const RateSchedule& schedule,
                                  int runs, std::uint64_t seed, int threads) {
  checkFits(scenario, schedule);
  ScheduleBook book;  // one version; its bracket is never read here
  ScheduleVersion only;
  only.version = 1;
  only.schedule = schedule;
  book.add(std::move(only));
  std::vector<double> costs(static_cast<std::size_t>(std::max(0, runs)), 0.0);
  forEachEpisode(
      runs, threads, {}, [&] { return EpisodeRunner(scenario); },
      [&](int e, EpisodeRunner& runner) {
        runner.start(seed, static_cast<std::uint64_t>(e));
        runner.advance(book, scenario.horizon_s);
        costs[static_cast<std::size_t>(e)] = runner.filter().cost();
      });
  return costs;
}

}  // namespace sensornet::evaluation
