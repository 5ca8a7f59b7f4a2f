#include "sensornet/core/monte_carlo.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <condition_variable>
#include <exception>
#include <limits>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "sensornet/core/arrival_timetable.hpp"
#include "sensornet/core/cdkf.hpp"
#include "sensornet/core/input_error.hpp"
#include "sensornet/core/poisson_arrivals.hpp"
#include "sensornet/core/random.hpp"
#include "sensornet/core/transition.hpp"

namespace sensornet {
namespace {

constexpr const char* kSource = "Monte Carlo";

void checkInputs(const Scenario& scenario, const RateSchedule& schedule,
                 const MonteCarloOptions& options) {
  if (options.runs < 1) {
    throw InputError(kSource, "runs", "an integer >= 1, got " + std::to_string(options.runs));
  }
  if (options.threads < 0) {
    throw InputError(kSource, "threads",
                     "an integer >= 0 (0 = all cores), got " + std::to_string(options.threads));
  }
  if (schedule.sensorCount() != scenario.sensorCount()) {
    throw InputError(kSource, "schedule",
                     "rates for " + std::to_string(scenario.sensorCount()) + " sensors, got " +
                         std::to_string(schedule.sensorCount()));
  }
  if (!(std::abs(schedule.horizon() - scenario.horizon_s) <= 1e-12 * scenario.horizon_s)) {
    throw InputError(kSource, "schedule.horizon",
                     "the scenario's horizon " + std::to_string(scenario.horizon_s) + ", got " +
                         std::to_string(schedule.horizon()));
  }
}

// Lower Cholesky factor L with L L' = X, as a dense matrix; throws InputError naming `field`.
Eigen::MatrixXd choleskyFactor(const Eigen::MatrixXd& X, const std::string& field) {
  const Eigen::LLT<Eigen::MatrixXd> llt(X);
  if (llt.info() != Eigen::Success) {
    throw InputError(kSource, field, "a positive definite matrix (Cholesky failed)");
  }
  return llt.matrixL();
}

void fillStandardNormal(Rng& rng, Eigen::Ref<Eigen::VectorXd> out) {
  for (Eigen::Index i = 0; i < out.size(); ++i) out(i) = rng.normal();
}

// What every episode shares, read-only across threads.
struct EpisodeModel {
  EpisodeModel(const Scenario& s, const RateSchedule& schedule, bool plant, ArrivalMode mode)
      : scenario(s), sampler(schedule), horizon_s(s.horizon_s), simulate_plant(plant) {
    if (mode == ArrivalMode::Timetable) timetable = timetableArrivals(schedule);
    const Eigen::Index n = s.plant.A.rows();
    initial_mean = s.plant.m0.size() == 0 ? Eigen::VectorXd::Zero(n) : s.plant.m0;
    terminal_weight = s.cost.WT.size() == 0 ? Eigen::MatrixXd::Identity(n, n) : s.cost.WT;
    if (!simulate_plant) return;
    initial_factor = choleskyFactor(s.plant.P0, "plant.P0");
    for (std::size_t j = 0; j < s.sensors.size(); ++j) {
      noise_factors.push_back(
          choleskyFactor(s.sensors[j].R, "sensors[" + std::to_string(j) + "].R"));
      max_rows = std::max(max_rows, s.sensors[j].H.rows());
    }
  }

  const Scenario& scenario;
  ArrivalSampler sampler;
  std::optional<std::vector<Arrival>> timetable;  // the fixed instants, in timetable mode
  double horizon_s;
  bool simulate_plant;
  Eigen::VectorXd initial_mean;
  Eigen::MatrixXd terminal_weight;
  Eigen::MatrixXd initial_factor;              // chol(P0), plant only
  std::vector<Eigen::MatrixXd> noise_factors;  // chol(R_j), plant only
  Eigen::Index max_rows = 0;                   // largest p_j
};

struct EpisodeOutcome {
  double cost = 0.0;
  double nees = 0.0;
  double squared_error = 0.0;
  int arrivals = 0;
};

// One worker's filter and buffers, sized once, so that the per-arrival loop does not allocate.
class EpisodeRunner {
 public:
  explicit EpisodeRunner(const EpisodeModel& model)
      : model_(model),
        filter_(model.scenario),
        truth_(model.initial_mean.size()),
        work_(model.initial_mean.size()),
        normals_(model.initial_mean.size()),
        measurement_(model.max_rows),
        measurement_noise_(model.max_rows),
        noise_ldlt_(model.initial_mean.size()),
        covariance_llt_(model.initial_mean.size()) {
    arrivals_.reserve(64);
  }

  EpisodeOutcome run(std::uint64_t seed, int episode) {
    Rng arrival_rng = Rng::keyed(seed, kMonteCarloArrivalStream, episode);
    Rng plant_rng = Rng::keyed(seed, kMonteCarloPlantStream, episode);
    if (model_.timetable) {
      arrivals_ = *model_.timetable;  // no allocation once the buffer has grown
    } else {
      model_.sampler.draw(arrival_rng, 0.0, model_.horizon_s, arrivals_);
    }

    filter_.reset();
    if (model_.simulate_plant) {
      // x(0) ~ N(m0, P0), eq. (1).
      fillStandardNormal(plant_rng, normals_);
      truth_ = model_.initial_mean;
      truth_.noalias() += model_.initial_factor * normals_;
    }
    double now = 0.0;
    for (const Arrival& arrival : arrivals_) {
      advance(arrival.time - now, plant_rng);
      now = arrival.time;
      if (model_.simulate_plant) {
        measure(arrival.sensor, plant_rng);
      } else {
        filter_.updateCovariance(arrival.sensor);
      }
    }
    advance(model_.horizon_s - now, plant_rng);

    EpisodeOutcome outcome;
    outcome.cost = filter_.cost();
    outcome.arrivals = static_cast<int>(arrivals_.size());
    if (model_.simulate_plant) scoreError(outcome);
    return outcome;
  }

 private:
  // Exact propagation of the filter, and of the truth: x(t+dt) = Phi x(t) + w, w ~ N(0, Qd).
  void advance(double dt, Rng& plant_rng) {
    if (!(dt > 0.0)) return;  // simultaneous arrivals: updates at one instant
    filter_.transition().over(dt, step_);
    filter_.propagateBy(step_, dt);
    if (!model_.simulate_plant) return;
    work_.noalias() = step_.Phi * truth_;
    truth_ = work_;
    // Qd = P' L D L' P by pivoted LDLT, which also copes with a singular Q; then
    // w = P' L D^{1/2} ξ has covariance Qd.
    noise_ldlt_.compute(step_.Qd);
    fillStandardNormal(plant_rng, normals_);
    normals_.array() *= noise_ldlt_.vectorD().array().max(0.0).sqrt();
    work_.noalias() = noise_ldlt_.matrixL() * normals_;
    work_ = noise_ldlt_.transpositionsP().transpose() * work_;
    truth_ += work_;
  }

  // z = H_j x + v, v ~ N(0, R_j), eq. (2), then the filter's update with it.
  void measure(int sensor, Rng& plant_rng) {
    const auto j = static_cast<std::size_t>(sensor);
    const Eigen::MatrixXd& H = model_.scenario.sensors[j].H;
    const Eigen::Index p = H.rows();
    auto z = measurement_.head(p);
    auto v = measurement_noise_.head(p);
    fillStandardNormal(plant_rng, v);
    z.noalias() = H * truth_;
    z.noalias() += model_.noise_factors[j] * v;
    filter_.update(sensor, z);
  }

  // NEES e' P(T)^{-1} e and the weighted squared error e' W_T e, e = x(T) - m(T).
  void scoreError(EpisodeOutcome& outcome) {
    work_ = truth_ - filter_.mean();
    normals_.noalias() = model_.terminal_weight * work_;
    outcome.squared_error = work_.dot(normals_);
    covariance_llt_.compute(filter_.covariance());
    covariance_llt_.matrixL().solveInPlace(work_);
    outcome.nees = work_.squaredNorm();
  }

  const EpisodeModel& model_;
  CdKalmanFilter filter_;
  IntervalTransition step_;
  std::vector<Arrival> arrivals_;
  Eigen::VectorXd truth_;
  Eigen::VectorXd work_;
  Eigen::VectorXd normals_;
  Eigen::VectorXd measurement_;
  Eigen::VectorXd measurement_noise_;
  Eigen::LDLT<Eigen::MatrixXd> noise_ldlt_;
  Eigen::LLT<Eigen::MatrixXd> covariance_llt_;
};

// Completed-episode count shared by the workers, followed by the calling thread, which is the
// only one that calls the progress callback. The first worker error is kept for rethrowing.
class ProgressBoard {
 public:
  void add(int episodes) {
    {
      const std::lock_guard lock(mutex_);
      done_ += episodes;
    }
    changed_.notify_one();
  }

  void fail(std::exception_ptr error) {
    {
      const std::lock_guard lock(mutex_);
      if (!error_) error_ = std::move(error);
    }
    changed_.notify_one();
  }

  // Blocks until all `total` episodes are done or a worker failed, calling report (if set)
  // after every change seen.
  void follow(int total, const std::function<void(int, int)>& report) {
    int reported = 0;
    while (true) {
      int done = 0;
      {
        std::unique_lock lock(mutex_);
        changed_.wait(lock, [&] { return error_ || done_ != reported; });
        if (error_) return;
        done = done_;
      }
      if (report) report(done, total);
      if (done >= total) return;
      reported = done;
    }
  }

  [[nodiscard]] std::exception_ptr error() const {
    const std::lock_guard lock(mutex_);
    return error_;
  }

 private:
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  int done_ = 0;
  std::exception_ptr error_;
};

int resolveThreadCount(int requested, int runs) {
  int threads = requested;
  if (threads == 0) threads = static_cast<int>(std::thread::hardware_concurrency());
  return std::clamp(threads, 1, runs);
}

// Runs every episode once, on `thread_count` workers that take chunks of consecutive episodes
// from an atomic counter; outcome e is written to slot e, so the partition does not matter.
std::vector<EpisodeOutcome> runEpisodes(const EpisodeModel& model,
                                        const MonteCarloOptions& options, int thread_count) {
  const int runs = options.runs;
  const int chunk = std::clamp(runs / (16 * thread_count), 1, 256);
  std::vector<EpisodeOutcome> outcomes(static_cast<std::size_t>(runs));
  std::atomic<int> next{0};
  ProgressBoard board;
  {
    std::vector<std::jthread> workers;
    workers.reserve(static_cast<std::size_t>(thread_count));
    for (int w = 0; w < thread_count; ++w) {
      workers.emplace_back([&](const std::stop_token& stop) {
        try {
          EpisodeRunner runner(model);
          while (!stop.stop_requested()) {
            const int begin = next.fetch_add(chunk);
            if (begin >= runs) break;
            const int end = std::min(begin + chunk, runs);
            for (int e = begin; e < end; ++e) {
              outcomes[static_cast<std::size_t>(e)] = runner.run(options.seed, e);
            }
            board.add(end - begin);
          }
        } catch (...) {
          board.fail(std::current_exception());
        }
      });
    }
    board.follow(runs, options.progress);
  }  // the jthreads are asked to stop and joined here, also when progress throws
  if (const std::exception_ptr error = board.error()) std::rethrow_exception(error);
  return outcomes;
}

struct SampleMoments {
  double mean = 0.0;
  double std_dev = 0.0;
};

// Two passes around the first value, so that equal values give exactly that value as mean and
// exactly zero spread, and large common offsets do not cancel.
SampleMoments momentsOf(const std::vector<double>& values) {
  const double shift = values.front();
  const auto count = static_cast<double>(values.size());
  double sum = 0.0;
  for (double v : values) sum += v - shift;
  const double mean_offset = sum / count;
  double squares = 0.0;
  for (double v : values) squares += (v - shift - mean_offset) * (v - shift - mean_offset);
  SampleMoments moments;
  moments.mean = shift + mean_offset;
  moments.std_dev = values.size() > 1 ? std::sqrt(squares / (count - 1.0)) : 0.0;
  return moments;
}

double meanOf(const std::vector<double>& values) {
  double sum = 0.0;
  for (double v : values) sum += v;
  return sum / static_cast<double>(values.size());
}

MonteCarloResult summarize(const std::vector<EpisodeOutcome>& outcomes, bool simulate_plant) {
  MonteCarloResult result;
  result.runs = static_cast<int>(outcomes.size());
  result.episode_costs.reserve(outcomes.size());
  double arrivals = 0.0;
  for (const EpisodeOutcome& o : outcomes) {
    result.episode_costs.push_back(o.cost);
    arrivals += o.arrivals;
    if (simulate_plant) {
      result.episode_nees.push_back(o.nees);
      result.episode_squared_errors.push_back(o.squared_error);
    }
  }
  const SampleMoments cost = momentsOf(result.episode_costs);
  const double runs = static_cast<double>(result.runs);
  result.mean = cost.mean;
  result.std_dev = cost.std_dev;
  result.ci95 = result.runs > 1 ? 1.96 * cost.std_dev / std::sqrt(runs)
                                : std::numeric_limits<double>::infinity();
  result.arrivals_mean = arrivals / runs;
  if (simulate_plant) {
    result.nees_mean = meanOf(result.episode_nees);
    result.squared_error_mean = meanOf(result.episode_squared_errors);
  }
  return result;
}

}  // namespace

MonteCarloResult evaluateSchedule(const Scenario& scenario, const RateSchedule& schedule,
                                  const MonteCarloOptions& options) {
  checkInputs(scenario, schedule, options);
  const EpisodeModel model(scenario, schedule, options.simulate_plant, options.arrivals);
  const int threads = resolveThreadCount(options.threads, options.runs);
  return summarize(runEpisodes(model, options, threads), options.simulate_plant);
}

}  // namespace sensornet
