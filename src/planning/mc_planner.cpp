#include "sensornet/planning/mc_planner.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <exception>
#include <functional>
#include <limits>
#include <mutex>
#include <string>
#include <thread>
#include <utility>

#include "planning_problem.hpp"
#include "sensornet/core/cdkf.hpp"
#include "sensornet/core/input_error.hpp"
#include "sensornet/core/poisson_arrivals.hpp"
#include "sensornet/core/random.hpp"
#include "sensornet/core/student_t.hpp"
#include "sensornet/core/surrogate.hpp"
#include "sensornet/core/transition.hpp"

namespace sensornet {
namespace {

constexpr const char* kSource = "mc planner";
constexpr std::uint64_t kProbeStream = 0x6d632d70726f6265ULL;      // "mc-probe"
// Seeds of the planner's stages, mixed with the request's seed.
constexpr std::uint64_t kScreeningStage = 1;
constexpr std::uint64_t kAcceptanceStage = 2;
constexpr std::uint64_t kReportStage = 3;
constexpr std::uint64_t kConfirmationStage = 4;
constexpr std::uint64_t kGradientStage = 100;
constexpr int kMaxRaceFactor = 8;      // the race among the starts grows to 8x its first sample
constexpr double kRaceTolerance = 0.005;  // starts within 0.5% of each other count as equal
constexpr int kMaxFailures = 4;  // unsuccessful gradient steps in a row that end the refinement
constexpr int kBlock = 8;  // episodes per unit of parallel work (fixed: results do not depend
                           // on the thread count)

std::uint64_t stageSeed(std::uint64_t seed, std::uint64_t stage) {
  return mix64(seed ^ mix64(stage + 0x9e3779b97f4a7c15ULL));
}

struct Segment {
  double start = 0.0;
  double end = 0.0;
  int interval = 0;
};

// The pieces of [t0, T] with constant rates (the rule of the surrogate transcription: a start
// within 1e-12 T of the next boundary starts the next interval).
std::vector<Segment> segmentsFrom(const Scenario& scenario, double t0) {
  const int count = scenario.intervals;
  const double horizon = scenario.horizon_s;
  const double h = scenario.intervalLength();
  auto boundary = [&](int k) { return k >= count ? horizon : k * h; };
  std::vector<Segment> segments;
  if (!(t0 < horizon)) return segments;
  int k = std::min(count - 1, static_cast<int>(std::floor(t0 / h)));
  while (k + 1 < count && boundary(k + 1) - t0 <= 1e-12 * horizon) ++k;
  segments.push_back({t0, boundary(k + 1), k});
  for (int i = k + 1; i < count; ++i) segments.push_back({boundary(i), boundary(i + 1), i});
  return segments;
}

// Runs body(block, worker) for blocks 0..blocks-1 on `threads` workers, each with its own
// state made by make(); the first exception is rethrown after all workers have stopped.
template <typename State, typename Make, typename Body>
void forEachBlock(int blocks, int threads, const Make& make, const Body& body) {
  std::atomic<int> next{0};
  std::atomic<bool> failed{false};
  std::exception_ptr error;
  std::mutex error_mutex;
  auto work = [&] {
    try {
      State state = make();
      for (int b = next.fetch_add(1); b < blocks && !failed; b = next.fetch_add(1)) {
        body(b, state);
      }
    } catch (...) {
      const std::lock_guard lock(error_mutex);
      if (!error) error = std::current_exception();
      failed = true;
    }
  };
  const int count = std::clamp(threads, 1, std::max(1, blocks));
  {
    std::vector<std::jthread> workers;
    for (int w = 1; w < count; ++w) workers.emplace_back(work);
    work();
  }
  if (error) std::rethrow_exception(error);
}

// One worker's filter and buffers.
class EpisodeWorker {
 public:
  EpisodeWorker(const Scenario& scenario, const std::vector<Segment>& segments,
                const Eigen::MatrixXd& start_covariance)
      : scenario_(scenario),
        segments_(segments),
        start_covariance_(start_covariance),
        filter_(scenario),
        probe_(scenario),
        zero_mean_(Eigen::VectorXd::Zero(scenario.stateDim())) {}

  // Arrivals of all sensors in [t0, T), sorted, for the delivered rates of this episode: each
  // sensor's unit-rate points mapped through the inverse of its integrated rate.
  void drawArrivals(const Eigen::MatrixXd& delivered, std::uint64_t seed, long long episode) {
    arrivals_.clear();
    for (int j = 0; j < static_cast<int>(delivered.cols()); ++j) {
      Rng rng = Rng::keyed(seed, kTimeChangeStream, static_cast<std::uint64_t>(episode),
                           static_cast<std::uint64_t>(j));
      double point = rng.exponential(1.0);
      double integrated = 0.0;  // Λ_j at the start of the segment
      for (const Segment& s : segments_) {
        const double rate = delivered(s.interval, j);
        if (!(rate > 0.0)) continue;
        const double top = integrated + rate * (s.end - s.start);
        while (point < top) {
          const double t = s.start + (point - integrated) / rate;
          if (t < s.end) arrivals_.push_back(Arrival{t, j});
          point += rng.exponential(1.0);
        }
        integrated = top;
      }
    }
    std::sort(arrivals_.begin(), arrivals_.end(), [](const Arrival& a, const Arrival& b) {
      return a.time < b.time || (a.time == b.time && a.sensor < b.sensor);
    });
  }

  double cost(const Eigen::MatrixXd& delivered, std::uint64_t seed, long long episode) {
    drawArrivals(delivered, seed, episode);
    restart(filter_);
    for (const Arrival& a : arrivals_) {
      filter_.propagateTo(a.time);
      filter_.updateCovariance(a.sensor);
    }
    filter_.propagateTo(scenario_.horizon_s);
    return filter_.cost();
  }

  // Adds this episode's add-one-point estimate into `gradient`; returns J(N).
  double addGradient(const Eigen::MatrixXd& delivered, std::uint64_t seed, long long episode,
                     const std::vector<int>& in_service, int sensors, Eigen::MatrixXd& gradient) {
    drawArrivals(delivered, seed, episode);
    storeForwardPath();
    const double base = filter_.cost();
    const int pool = static_cast<int>(in_service.size());
    const int picks = (sensors <= 0 || sensors >= pool) ? pool : sensors;
    if (pool == 0) return base;
    const double weight = static_cast<double>(pool) / picks;
    Rng rng = Rng::keyed(seed, kProbeStream, static_cast<std::uint64_t>(episode));
    chosen_ = in_service;
    for (const Segment& s : segments_) {
      const double u = s.start + rng.uniform() * (s.end - s.start);
      pickSensors(rng, picks);
      const std::size_t before = arrivalsBefore(u);
      const double reach = prepareProbe(u, before);
      for (int c = 0; c < picks; ++c) {
        const int j = chosen_[static_cast<std::size_t>(c)];
        const double extra = probeCost(u, j, before, reach);
        gradient(s.interval, j) += weight * (s.end - s.start) * (extra - base);
      }
    }
    return base;
  }

 private:
  void restart(CdKalmanFilter& filter) const {
    filter.reset(segments_.empty() ? scenario_.horizon_s : segments_.front().start, zero_mean_,
                 start_covariance_);
  }

  // The forward pass, keeping the covariance after every arrival, the cost so far, and the
  // transitions of the gaps between arrivals (gap i ends at arrival i; the last at T).
  void storeForwardPath() {
    restart(filter_);
    const std::size_t count = arrivals_.size();
    after_.resize(count);
    cost_at_.resize(count);
    gaps_.resize(count + 1);
    double now = filter_.time();
    for (std::size_t i = 0; i <= count; ++i) {
      const double t = i < count ? arrivals_[i].time : scenario_.horizon_s;
      filter_.transition().over(t - now, gaps_[i]);
      filter_.propagateBy(gaps_[i], t - now);
      now = t;
      if (i == count) break;
      filter_.updateCovariance(arrivals_[i].sensor);
      after_[i] = filter_.covariance();
      cost_at_[i] = filter_.runningCost();
    }
  }

  // Partial Fisher-Yates: the first `picks` entries of chosen_ become a uniform random subset.
  void pickSensors(Rng& rng, int picks) {
    const auto pool = chosen_.size();
    if (static_cast<std::size_t>(picks) >= pool) return;
    for (std::size_t c = 0; c < static_cast<std::size_t>(picks); ++c) {
      const auto r = c + static_cast<std::size_t>(rng.uniform() * static_cast<double>(pool - c));
      std::swap(chosen_[c], chosen_[std::min(r, pool - 1)]);
    }
  }

  [[nodiscard]] std::size_t arrivalsBefore(double u) const {
    return static_cast<std::size_t>(
        std::upper_bound(arrivals_.begin(), arrivals_.end(), u,
                         [](double t, const Arrival& a) { return t < a.time; }) -
        arrivals_.begin());
  }

  // P(u-) and the running cost up to u on the forward path, and the transition from u to the
  // next arrival (or T); returns the time the latter reaches.
  double prepareProbe(double u, std::size_t before) {
    const double from = before == 0 ? filterStart() : arrivals_[before - 1].time;
    if (before == 0) {
      restart(probe_);
    } else {
      probe_.reset(from, zero_mean_, after_[before - 1]);
    }
    probe_.propagateTo(u);
    covariance_at_u_ = probe_.covariance();
    cost_to_u_ = (before == 0 ? 0.0 : cost_at_[before - 1]) + probe_.runningCost();
    const double reach = before < arrivals_.size() ? arrivals_[before].time : scenario_.horizon_s;
    probe_.transition().over(reach - u, from_u_);
    return reach;
  }

  double filterStart() const {
    return segments_.empty() ? scenario_.horizon_s : segments_.front().start;
  }

  // J(N + one arrival of sensor j at u), re-running from u over the stored gaps.
  double probeCost(double u, int j, std::size_t before, double reach) {
    probe_.reset(u, zero_mean_, covariance_at_u_);
    probe_.updateCovariance(j);
    probe_.propagateBy(from_u_, reach - u);
    for (std::size_t i = before; i < arrivals_.size(); ++i) {
      probe_.updateCovariance(arrivals_[i].sensor);
      const double next = i + 1 < arrivals_.size() ? arrivals_[i + 1].time : scenario_.horizon_s;
      probe_.propagateBy(gaps_[i + 1], next - arrivals_[i].time);
    }
    return cost_to_u_ + probe_.cost();
  }

  const Scenario& scenario_;
  const std::vector<Segment>& segments_;
  const Eigen::MatrixXd& start_covariance_;
  CdKalmanFilter filter_;
  CdKalmanFilter probe_;
  Eigen::VectorXd zero_mean_;
  std::vector<Arrival> arrivals_;
  std::vector<Eigen::MatrixXd> after_;
  std::vector<double> cost_at_;
  std::vector<IntervalTransition> gaps_;
  std::vector<int> chosen_;
  Eigen::MatrixXd covariance_at_u_;
  double cost_to_u_ = 0.0;
  IntervalTransition from_u_;
};

int resolveThreads(int requested) {
  if (requested > 0) return requested;
  return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

}  // namespace

RealizedCostSampler::RealizedCostSampler(const Scenario& scenario, const PlanRequest& request,
                                         int threads)
    : scenario_(scenario),
      start_time_(request.start_time),
      start_covariance_(request.start_covariance ? *request.start_covariance : scenario.plant.P0),
      delivery_(request.delivery ? *request.delivery
                                 : Eigen::MatrixXd::Ones(scenario.intervals,
                                                         scenario.sensorCount())),
      first_interval_(scenario.intervals),
      threads_(resolveThreads(threads)) {
  const std::vector<Segment> segments = segmentsFrom(scenario, start_time_);
  if (!segments.empty()) first_interval_ = segments.front().interval;
}

std::vector<double> RealizedCostSampler::episodeCosts(const Eigen::MatrixXd& rates,
                                                      std::uint64_t seed, long long first,
                                                      int count) const {
  const Eigen::MatrixXd delivered = rates.cwiseProduct(delivery_);
  const std::vector<Segment> segments = segmentsFrom(scenario_, start_time_);
  std::vector<double> costs(static_cast<std::size_t>(std::max(count, 0)));
  const int blocks = (count + kBlock - 1) / kBlock;
  forEachBlock<EpisodeWorker>(
      blocks, threads_,
      [&] { return EpisodeWorker(scenario_, segments, start_covariance_); },
      [&](int b, EpisodeWorker& worker) {
        for (int e = b * kBlock; e < std::min(count, (b + 1) * kBlock); ++e) {
          costs[static_cast<std::size_t>(e)] = worker.cost(delivered, seed, first + e);
        }
      });
  return costs;
}

RealizedCostSampler::Gradient RealizedCostSampler::gradient(const Eigen::MatrixXd& rates,
                                                            std::uint64_t seed, int count,
                                                            const std::vector<int>& in_service,
                                                            int sensors) const {
  const Eigen::MatrixXd delivered = rates.cwiseProduct(delivery_);
  const std::vector<Segment> segments = segmentsFrom(scenario_, start_time_);
  const int blocks = (count + kBlock - 1) / kBlock;
  std::vector<Eigen::MatrixXd> sums(static_cast<std::size_t>(blocks),
                                    Eigen::MatrixXd::Zero(rates.rows(), rates.cols()));
  std::vector<double> costs(static_cast<std::size_t>(blocks), 0.0);
  forEachBlock<EpisodeWorker>(
      blocks, threads_,
      [&] { return EpisodeWorker(scenario_, segments, start_covariance_); },
      [&](int b, EpisodeWorker& worker) {
        const auto slot = static_cast<std::size_t>(b);
        for (int e = b * kBlock; e < std::min(count, (b + 1) * kBlock); ++e) {
          costs[slot] += worker.addGradient(delivered, seed, e, in_service, sensors, sums[slot]);
        }
      });
  Gradient result;
  result.gradient = Eigen::MatrixXd::Zero(rates.rows(), rates.cols());
  for (int b = 0; b < blocks; ++b) {
    result.gradient += sums[static_cast<std::size_t>(b)];
    result.cost += costs[static_cast<std::size_t>(b)];
  }
  result.gradient = result.gradient.cwiseProduct(delivery_) / count;  // chain rule: λ ↦ d ⊙ λ
  result.cost /= count;
  return result;
}

namespace {

double meanOf(const std::vector<double>& v) {
  double sum = 0.0;
  for (double x : v) sum += x;
  return sum / static_cast<double>(v.size());
}

double stdDevOf(const std::vector<double>& v) {
  const double m = meanOf(v);
  double squares = 0.0;
  for (double x : v) squares += (x - m) * (x - m);
  return v.size() > 1 ? std::sqrt(squares / static_cast<double>(v.size() - 1)) : 0.0;
}

void checkOptions(const RealizedCostOptions& o) {
  auto atLeast = [](const char* field, long long value, long long least) {
    if (value < least) {
      throw InputError(kSource, field,
                       "an integer >= " + std::to_string(least) + ", got " +
                           std::to_string(value));
    }
  };
  atLeast("threads", o.threads, 0);
  atLeast("screening_episodes", o.screening_episodes, 2);
  atLeast("gradient_episodes", o.gradient_episodes, 1);
  atLeast("gradient_sensors", o.gradient_sensors, 0);
  atLeast("acceptance_episodes", o.acceptance_episodes, 2);
  atLeast("report_episodes", o.report_episodes, 2);
  // The race of up to four starts, the refined schedule, and the confirmation's two schedules.
  const long long fixed = 10LL * o.screening_episodes + 7LL * o.acceptance_episodes +
                          static_cast<long long>(o.report_episodes);
  atLeast("max_episodes", o.max_episodes, fixed);
}

// The state of the search: the planning problem (projection, planned rows), the sampler, the
// screening sample and the budget.
class RealizedCostSearch {
 public:
  RealizedCostSearch(const Scenario& scenario, const PlanRequest& request,
                     planning::Clock::time_point start)
      : request_(request),
        options_(request.realized),
        problem_(scenario, request, SurrogateForm::Information),
        sampler_(scenario, request, request.realized.threads),
        start_(start) {}

  [[nodiscard]] planning::PlanningProblem& problem() { return problem_; }
  [[nodiscard]] long long episodes() const { return episodes_; }
  [[nodiscard]] int iterations() const { return iterations_; }
  [[nodiscard]] int gradients() const { return gradients_; }

  // The screening sample: the same episodes for every candidate. Its size is fixed by the first
  // call: screening_episodes, unless screening `candidates` schedules at the episode time of a
  // pilot (the first 200 episodes) would take more than 30% of max_seconds; then it shrinks to
  // fit, to no less than 200 episodes.
  std::vector<double> screen(const Eigen::MatrixXd& rates, int candidates = 1) {
    const std::uint64_t seed = stageSeed(options_.seed, kScreeningStage);
    if (screening_size_ > 0) return sample(rates, seed, screening_size_);
    const int pilot = std::min(200, options_.screening_episodes);
    std::vector<double> costs = sample(rates, seed, pilot);
    const double affordable =
        0.3 * request_.max_seconds / (std::max(1, candidates) * std::max(episodeSeconds(), 1e-9));
    // Clamped as a double: the affordable count can exceed the range of int.
    screening_size_ = std::max(
        pilot, static_cast<int>(std::min(affordable, static_cast<double>(options_.screening_episodes))));
    if (screening_size_ > pilot) {
      episodes_ += screening_size_ - pilot;
      const std::vector<double> rest =
          sampler_.episodeCosts(rates, seed, pilot, screening_size_ - pilot);
      costs.insert(costs.end(), rest.begin(), rest.end());
    }
    return costs;
  }

  // J(P) of episodes first..first+count-1 of `seed`.
  std::vector<double> sample(const Eigen::MatrixXd& rates, std::uint64_t seed, int count,
                             long long first = 0) {
    const auto begin = planning::Clock::now();
    episodes_ += count;
    std::vector<double> costs = sampler_.episodeCosts(rates, seed, first, count);
    sampled_ += count;
    sample_seconds_ += planning::secondsSince(begin);
    return costs;
  }

  // Seconds left of max_seconds.
  [[nodiscard]] double secondsLeft() const {
    return request_.max_seconds - planning::secondsSince(start_);
  }

  // Wall time of one sampled episode so far (0 before any).
  [[nodiscard]] double episodeSeconds() const {
    return sampled_ > 0 ? sample_seconds_ / static_cast<double>(sampled_) : 0.0;
  }

  // The acceptance and report sample sizes: as configured, unless their predicted time exceeds
  // a quarter of max_seconds; then both shrink in proportion, to no less than 1000 episodes.
  // `schedules`: how many the acceptance stage scores.
  [[nodiscard]] std::pair<int, int> finalSizes(int schedules) const {
    const double predicted =
        (schedules * static_cast<double>(options_.acceptance_episodes) + options_.report_episodes) *
        episodeSeconds();
    const double budget = 0.25 * request_.max_seconds;
    if (!(predicted > budget)) return {options_.acceptance_episodes, options_.report_episodes};
    const double f = budget / predicted;
    auto shrink = [f](int count) {
      return std::min(count, std::max(1000, static_cast<int>(f * count)));
    };
    return {shrink(options_.acceptance_episodes), shrink(options_.report_episodes)};
  }

  // Projected stochastic gradient refinement from `rates` (screening mean `value`); returns the
  // status of the refinement and leaves the best point in `rates`.
  std::string refine(Eigen::MatrixXd& rates, double& value, int final_schedules) {
    double fraction = 0.25;
    int failures = 0;
    const auto [acceptance, report] = finalSizes(final_schedules);
    const long long reserve = static_cast<long long>(final_schedules) * acceptance + report;
    // Leave time for the final stages (with a margin of 20%).
    const double deadline =
        request_.max_seconds - 1.2 * static_cast<double>(reserve) * episodeSeconds();
    double last_iteration = 0.0;
    for (int it = 0;; ++it) {
      const double elapsed = planning::secondsSince(start_);
      if (it >= request_.max_iterations) return "max_iterations";
      if (elapsed + last_iteration > deadline) return "time_limit";
      if (episodes_ + options_.gradient_episodes + 2LL * options_.screening_episodes + reserve >
          options_.max_episodes) {
        return "episode_limit";
      }
      const RealizedCostSampler::Gradient g = sampler_.gradient(
          rates, stageSeed(options_.seed, kGradientStage + static_cast<std::uint64_t>(it)),
          options_.gradient_episodes, problem_.inService(), options_.gradient_sensors);
      episodes_ += options_.gradient_episodes;
      ++gradients_;
      const double largest =
          problem_.plannedIntervals() == 0
              ? 0.0
              : g.gradient.bottomRows(problem_.plannedIntervals()).cwiseAbs().maxCoeff();
      if (!(largest > 0.0) || !std::isfinite(largest)) return "stalled";
      bool moved = false;
      for (double trial : {fraction, fraction / 4.0}) {
        const Eigen::MatrixXd candidate = problem_.projected(
            rates - (trial * problem_.rateUnit() / largest) * g.gradient);
        const double candidate_value = meanOf(screen(candidate));
        if (candidate_value < value) {
          rates = candidate;
          value = candidate_value;
          fraction = std::min(1.0, 2.0 * trial);
          moved = true;
          break;
        }
      }
      iterations_ = it + 1;
      if (moved) {
        failures = 0;
      } else {
        fraction /= 16.0;
        if (++failures >= kMaxFailures || fraction < 1e-4) return "stalled";
      }
      last_iteration = planning::secondsSince(start_) - elapsed;
      if (request_.progress) {
        const PlanProgress p{iterations_, value, planning::secondsSince(start_)};
        if (!request_.progress(p)) return "stopped";
      }
    }
  }

 private:
  const PlanRequest& request_;
  const RealizedCostOptions& options_;
  planning::PlanningProblem problem_;
  RealizedCostSampler sampler_;
  planning::Clock::time_point start_;
  int screening_size_ = 0;       // fixed by the first screen()
  long long episodes_ = 0;
  long long sampled_ = 0;        // episodes of sample(), and their wall time
  double sample_seconds_ = 0.0;
  int iterations_ = 0;
  int gradients_ = 0;
};

struct Candidate {
  Eigen::MatrixXd rates;
  double value = 0.0;
};

// The surrogate plans of the same request (info, cov), the uniform rates, the warm start.
std::vector<Eigen::MatrixXd> surrogateStarts(const Scenario& scenario, const PlanRequest& request,
                                             planning::PlanningProblem& problem) {
  std::vector<Eigen::MatrixXd> starts;
  for (PlanSurrogate s :
       {PlanSurrogate::Information, PlanSurrogate::Covariance, PlanSurrogate::Uniform}) {
    PlanRequest sub = request;
    sub.surrogate = s;
    sub.progress = nullptr;
    sub.max_seconds = std::max(1.0, 0.2 * request.max_seconds);
    starts.push_back(planSchedule(scenario, sub).schedule.rates());
  }
  if (request.warm_start) starts.push_back(problem.projected(request.warm_start->rates()));
  return starts;
}

// A paired one-sided t-test at level 5% on the same episodes: E[candidate - reference] < 0.
bool significantlyBetter(const std::vector<double>& candidate,
                         const std::vector<double>& reference) {
  std::vector<double> d(candidate.size());
  for (std::size_t e = 0; e < d.size(); ++e) d[e] = candidate[e] - reference[e];
  const double n = static_cast<double>(d.size());
  return meanOf(d) + studentTQuantile(0.95, n - 1.0) * stdDevOf(d) / std::sqrt(n) < 0.0;
}

// One start in the race: its rates and its costs on the race's episodes so far.
struct RaceEntry {
  Eigen::MatrixXd rates;
  std::vector<double> costs;
};

// The start with the lowest E[J], chosen on fresh episodes of `seed` by racing: every start
// still in the race is scored on the same episodes (paired); a start drops out when its paired
// difference to the leader is significantly positive (one-sided 2.5%) or when the two are equal
// within kRaceTolerance of the leader's mean (95% interval of the difference inside it; the
// leader stays). While two or more remain, the sample doubles, up to kMaxRaceFactor times the
// first `episodes`, as long as the time left after the doubling still holds the report sample
// (`reserve` episodes). Small samples of a heavy-tailed J picked the wrong start before
// (bench/README.md); the race spends episodes only where the starts are close.
RaceEntry raceStarts(RealizedCostSearch& search, const std::vector<Eigen::MatrixXd>& starts,
                     std::uint64_t seed, int episodes, int reserve) {
  std::vector<RaceEntry> race;
  for (const Eigen::MatrixXd& s : starts) race.push_back({s, search.sample(s, seed, episodes)});
  auto leaderOf = [&race] {
    return std::min_element(race.begin(), race.end(), [](const RaceEntry& a, const RaceEntry& b) {
      return meanOf(a.costs) < meanOf(b.costs);
    });
  };
  for (int factor = 1;; factor *= 2) {
    const auto leader = leaderOf();
    const std::vector<double>& l = leader->costs;
    const double n = static_cast<double>(l.size());
    const double t = studentTQuantile(0.975, n - 1.0);
    std::vector<RaceEntry> still;
    for (auto it = race.begin(); it != race.end(); ++it) {
      if (it == leader) continue;
      std::vector<double> d(l.size());
      for (std::size_t e = 0; e < d.size(); ++e) d[e] = it->costs[e] - l[e];
      const double half = t * stdDevOf(d) / std::sqrt(n);
      const bool worse = meanOf(d) - half > 0.0;
      const bool equal = meanOf(d) + half < kRaceTolerance * meanOf(l);
      if (!worse && !equal) still.push_back(std::move(*it));
    }
    still.push_back(std::move(*leader));
    race = std::move(still);
    const auto sampled = static_cast<long long>(race.back().costs.size());
    const long long more = static_cast<long long>(race.size()) * sampled;
    const double needed =
        1.2 * static_cast<double>(more + reserve) * search.episodeSeconds();
    if (race.size() == 1 || factor >= kMaxRaceFactor || needed > search.secondsLeft()) break;
    for (RaceEntry& entry : race) {
      const std::vector<double> extra =
          search.sample(entry.rates, seed, static_cast<int>(sampled), sampled);
      entry.costs.insert(entry.costs.end(), extra.begin(), extra.end());
    }
  }
  return std::move(*leaderOf());
}

}  // namespace

PlanResult planForRealizedCost(const Scenario& scenario, const PlanRequest& request) {
  checkOptions(request.realized);
  const auto start = planning::Clock::now();
  const std::vector<Eigen::MatrixXd> starts = [&] {
    planning::PlanningProblem problem(scenario, request, SurrogateForm::Information);
    return surrogateStarts(scenario, request, problem);
  }();
  RealizedCostSearch search(scenario, request, start);

  // The reference: the best of the surrogate plans (and warm start) on the screening sample.
  Candidate reference{starts.front(), std::numeric_limits<double>::infinity()};
  const int candidates = static_cast<int>(starts.size()) + 6;
  for (const Eigen::MatrixXd& s : starts) {
    const double v = meanOf(search.screen(s, candidates));
    if (v < reference.value) reference = {s, v};
  }
  // The start: the best of the reference and the mixtures of cov with info and with uniform.
  Candidate best = reference;
  for (const Eigen::MatrixXd& other : {starts[0], starts[2]}) {
    for (double a : {0.25, 0.5, 0.75}) {
      const Eigen::MatrixXd mix = a * starts[1] + (1.0 - a) * other;
      const double v = meanOf(search.screen(mix));
      if (v < best.value) best = {mix, v};
    }
  }
  if (request.progress) {
    (void)request.progress(PlanProgress{0, best.value, planning::secondsSince(start)});
  }

  PlanResult result;
  // Scored at the end on samples of the acceptance size: the starts (race), the refined
  // schedule, and the refined schedule and the reference again (confirmation).
  const int final_schedules = static_cast<int>(starts.size()) + 3;
  if (search.problem().variables() > 0) {
    (void)search.refine(best.rates, best.value, final_schedules);
  }

  // On fresh episodes: the reference is chosen again among the starts by a race (the screening
  // sample may be small), then the paired test of refined minus reference, one-sided at 5%.
  // Choosing the reference on the same sample favours it, so the test only gets more
  // conservative.
  const RealizedCostOptions& o = request.realized;
  const auto [acceptance, report] = search.finalSizes(final_schedules);
  const std::uint64_t seed = stageSeed(o.seed, kAcceptanceStage);
  std::vector<double> r;
  {
    RaceEntry leader = raceStarts(search, starts, seed, acceptance, report);
    reference.rates = std::move(leader.rates);
    r = std::move(leader.costs);
  }
  Eigen::MatrixXd chosen = reference.rates;
  result.status = PlanStatus::KeptStart;
  std::vector<double> a;
  if (best.rates != reference.rates) a = search.sample(best.rates, seed, static_cast<int>(r.size()));
  if (!a.empty() && significantlyBetter(a, r)) {
    // Confirmed with as many fresh episodes again, the test repeated on both samples together:
    // J(P) is heavy-tailed where a mode is unstable and rarely observed, and a sample that
    // misses the refined schedule's rare disasters passes it however large it is (n = 4 of the
    // paper's family: accepted on 10000 episodes, then 0.0810 +- 0.0940 on the report sample
    // against the reference's 0.0315 +- 0.024). The disasters now have to be missing from twice
    // the episodes, and a truly better schedule loses little: the test on the doubled sample
    // has more power than the first. Costs two samples of the acceptance size.
    const std::uint64_t confirmation = stageSeed(o.seed, kConfirmationStage);
    const int size = static_cast<int>(r.size());
    const std::vector<double> more_a = search.sample(best.rates, confirmation, size);
    const std::vector<double> more_r = search.sample(reference.rates, confirmation, size);
    a.insert(a.end(), more_a.begin(), more_a.end());
    std::vector<double> both_r = r;
    both_r.insert(both_r.end(), more_r.begin(), more_r.end());
    if (significantlyBetter(a, both_r)) {
      chosen = best.rates;
      result.status = PlanStatus::Improved;
    }
  }

  // The score: yet another fresh sample.
  const std::vector<double> scored =
      search.sample(chosen, stageSeed(o.seed, kReportStage), report);
  const double n = static_cast<double>(scored.size());
  result.schedule = RateSchedule(scenario.horizon_s, chosen);
  result.objective = meanOf(scored);
  result.objective_half_width = studentTQuantile(0.975, n - 1.0) * stdDevOf(scored) / std::sqrt(n);
  result.episodes = search.episodes();
  result.iterations = search.iterations();
  result.evaluations = search.gradients();
  result.kkt_residual = std::numeric_limits<double>::quiet_NaN();
  result.discretized_objective = std::numeric_limits<double>::quiet_NaN();
  RolloutOptions accurate;
  accurate.start_time = request.start_time;
  accurate.start_covariance = request.start_covariance;
  result.bracket = computeBracket(scenario, result.schedule, accurate);
  result.solve_seconds = planning::secondsSince(start);
  return result;
}

}  // namespace sensornet
