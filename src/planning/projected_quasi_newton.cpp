// The planner's default optimizer: a projected quasi-Newton method over the admissible rates.
//
// Each iteration finds the constraints that bind at x (Bertsekas' ε-active set, widened to the
// rates that the projected gradient step sends to zero: those whose reduced gradient pushes them
// down are held and sent to zero, and tight constraint rows whose multiplier estimate is
// positive stay tight), takes an L-BFGS direction in the tangent space of that face, and
// searches along the projection arc P(x + t d), so that many rates can reach zero in one step.
// The L-BFGS algebra runs on vectors of the free rates only (at M = 1000 a few hundred of
// 30000 rates are free near the solution); its 150 pairs are kept as N x M steps (about 70 MB
// at N = 30, M = 1000). For the information form its initial matrix is a diagonal estimate of
// the inverse Hessian, 1 / (tr S_j |g_kj|) up to the usual secant scale, instead of a multiple
// of the identity (the rates' curvatures differ by the sensors' noise and by the interval).
// When that fails to descend, it takes a spectral projected gradient step (Birgin, Martínez &
// Raydan, SIAM J. Optim. 10, 2000), which always does. Both steps use the scale-free problem
// (rates in units of the largest λ̄, cost in units of |J(start)|), every iterate is feasible, and
// the stopping test is PlanResult::kkt_residual <= tolerance.

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <deque>
#include <optional>
#include <utility>
#include <vector>

#include "planning_problem.hpp"

namespace sensornet::planning {
namespace {

using Eigen::MatrixXd;

constexpr int kMemory = 150;  // L-BFGS pairs (40: about 1.3x the iterations at n = 20, M = 30)
constexpr double kSufficientDecrease = 1e-4;  // Armijo
constexpr int kMaxBacktracks = 40;
constexpr int kMaxShortenings = 6;  // arc steps shortened without evaluation (t >= 1e-6)
constexpr double kMinScaledStep = 1e-10;
constexpr double kMaxScaledStep = 1e10;
constexpr double kMaxActiveWidth = 1e-3;    // ε never exceeds this many rate units

// The constraints binding at x and the orthogonal projection onto the directions that keep
// them binding: per planned interval, the rates held at zero, and the tight rows of C with a
// positive multiplier estimate (least squares on the free rates, g_F + C_AF' μ ≈ 0).
class BindingFace {
 public:
  // `gradient_point` is the projected gradient step P(x - α g): a rate it sends to zero is a
  // candidate for the bound however large it is now.
  BindingFace(const PlanningProblem& problem, const MatrixXd& x, const MatrixXd& gradient,
              const MatrixXd& gradient_point, double epsilon)
      : problem_(problem) {
    for (int k = problem.firstInterval(); k < problem.intervals(); ++k) {
      intervals_.push_back(bind(k, x, gradient, gradient_point, epsilon));
    }
    for (Interval& interval : intervals_) {
      interval.offset = free_count_;
      free_count_ += static_cast<Eigen::Index>(interval.free.size());
    }
  }

  // The component of v that keeps every binding constraint binding, as a vector over the free
  // rates (interval by interval): the L-BFGS algebra runs on these, not on N x M matrices.
  [[nodiscard]] Eigen::VectorXd compact(const MatrixXd& v) const {
    return compactOf([&v](int k, int j) { return v(k, j); });
  }
  // The same for v given transposed (M x N: sensor by interval, each interval contiguous).
  [[nodiscard]] Eigen::VectorXd compactOfTransposed(const MatrixXd& v_transposed) const {
    return compactOf([&v_transposed](int k, int j) { return v_transposed(j, k); });
  }

  template <typename Entry>
  [[nodiscard]] Eigen::VectorXd compactOf(const Entry& entry) const {
    Eigen::VectorXd out(free_count_);
    for (const Interval& interval : intervals_) {
      auto t = out.segment(interval.offset, static_cast<Eigen::Index>(interval.free.size()));
      for (std::size_t f = 0; f < interval.free.size(); ++f) {
        t(static_cast<Eigen::Index>(f)) = entry(interval.k, interval.free[f]);
      }
      if (interval.basis.cols() > 0) t -= interval.basis * (interval.basis.transpose() * t);
    }
    return out;
  }

  // The free entries of `entry(k, j)` in compact order, not projected.
  template <typename Entry>
  [[nodiscard]] Eigen::VectorXd gatherOf(const Entry& entry) const {
    Eigen::VectorXd out(free_count_);
    for (const Interval& interval : intervals_) {
      for (std::size_t f = 0; f < interval.free.size(); ++f) {
        out(interval.offset + static_cast<Eigen::Index>(f)) = entry(interval.k, interval.free[f]);
      }
    }
    return out;
  }

  // c (compact) projected onto the tangent space of the face, in place.
  void toTangent(Eigen::VectorXd& c) const {
    for (const Interval& interval : intervals_) {
      if (interval.basis.cols() == 0) continue;
      auto t = c.segment(interval.offset, static_cast<Eigen::Index>(interval.free.size()));
      t -= interval.basis * (interval.basis.transpose() * t);
    }
  }

  // The N x M matrix of a compact vector (0 off the free rates).
  [[nodiscard]] MatrixXd expand(const Eigen::VectorXd& c) const {
    MatrixXd out = MatrixXd::Zero(problem_.intervals(), problem_.rates().cols());
    for (const Interval& interval : intervals_) {
      for (std::size_t f = 0; f < interval.free.size(); ++f) {
        out(interval.k, interval.free[f]) = c(interval.offset + static_cast<Eigen::Index>(f));
      }
    }
    return out;
  }

  // Moves the free rates of `direction` so that x + direction lies on every binding row,
  // C_i (x + d) = b_i, by the least change in the span of the rows' normals. Two things need it.
  // The rate a held sensor gives up goes to the free ones, as the multipliers in the reduced
  // gradient assume (without it, sending rates to zero under a tight budget only leaves budget
  // unused); what it gives up is its rate, not the push -max(x, σ r): a push of a rate already
  // at zero is clipped by the projection and frees nothing. (Counting the push instead put the
  // step outside the rows wherever a zero rate was pushed, the projection bent it into ascent,
  // and the default scenario's plans, whose intervals have two binding rows, stalled: the reason
  // this was once done for a single binding row only.) And a row counts as binding while its
  // slack is within ε, which shrinks with the KKT residual: a tangent direction never used that
  // slack while the residual's projected-gradient step does, so the residual stayed at the
  // largest such slack over rateUnit, and ε with it. The default scenario's cov plan without
  // sensor 1, warm-started from the plan with it, stopped there after 500 iterations (residual
  // 1.3e-3: slacks up to 1.5e-2 held as binding under ε = 1.2e-2; bench/README.md).
  void moveOntoBindingRows(const MatrixXd& x, MatrixXd& direction) const {
    const MatrixXd& C = problem_.C();
    for (const Interval& interval : intervals_) {
      if (interval.rows.empty() || interval.basis.cols() == 0) continue;
      // What the free rates must add along each row: its slack, less what the other rates'
      // changes add (the free part of d is tangent, N_F' d_F = 0).
      Eigen::VectorXd missing(static_cast<Eigen::Index>(interval.rows.size()));
      for (std::size_t r = 0; r < interval.rows.size(); ++r) {
        const Eigen::Index row = interval.rows[r];
        double others = 0.0;
        for (Eigen::Index j = 0; j < C.cols(); ++j) {
          if (std::binary_search(interval.free.begin(), interval.free.end(), static_cast<int>(j))) {
            continue;
          }
          others += C(row, j) * std::max(direction(interval.k, j), -x(interval.k, j));
        }
        const double slack = problem_.b()(row) - C.row(row).dot(x.row(interval.k));
        missing(static_cast<Eigen::Index>(r)) = std::max(slack, 0.0) - others;
      }
      if (missing.isZero(0.0)) continue;
      // Δ = Q1 z with N_F' Δ = missing (least squares when the rows are dependent).
      const MatrixXd system = interval.normals.transpose() * interval.basis;
      const Eigen::VectorXd z = system.colPivHouseholderQr().solve(missing);
      const Eigen::VectorXd shift = interval.basis * z;
      for (std::size_t f = 0; f < interval.free.size(); ++f) {
        direction(interval.k, interval.free[f]) += shift(static_cast<Eigen::Index>(f));
      }
    }
  }

  // Faces with the same free rates and binding rows have the same tangent space.
  [[nodiscard]] bool sameTangentSpace(const BindingFace& other) const {
    if (intervals_.size() != other.intervals_.size()) return false;
    for (std::size_t i = 0; i < intervals_.size(); ++i) {
      if (intervals_[i].free != other.intervals_[i].free ||
          intervals_[i].rows != other.intervals_[i].rows) {
        return false;
      }
    }
    return true;
  }

  // The rates held at zero with their reduced gradient g + C_A' μ (> 0): the direction that
  // pushes them onto the bound.
  struct Push {
    int k;
    int j;
    double reduced;
  };
  [[nodiscard]] const std::vector<Push>& zeroPushes() const { return zero_pushes_; }

 private:
  struct Interval {
    int k = 0;
    std::vector<int> free;
    std::vector<int> rows;
    MatrixXd normals;  // |free| x |rows|: C_AF'
    MatrixXd basis;    // orthonormal basis of the range of normals
    Eigen::Index offset = 0;  // of its free rates in a compact vector
    Eigen::ColPivHouseholderQR<MatrixXd> qr;
  };

  static Eigen::VectorXd gather(const MatrixXd& v, const Interval& interval) {
    Eigen::VectorXd out(static_cast<Eigen::Index>(interval.free.size()));
    for (std::size_t f = 0; f < interval.free.size(); ++f) {
      out(static_cast<Eigen::Index>(f)) = v(interval.k, interval.free[f]);
    }
    return out;
  }

  // Tight rows touching a free rate, their normals and the multiplier estimate; rows with
  // μ_i <= 0 are released (one pass).
  Eigen::VectorXd bindRows(Interval& interval, const Eigen::VectorXd& lambda,
                           const MatrixXd& gradient, double epsilon) const {
    const MatrixXd& C = problem_.C();
    for (int pass = 0; pass < 2; ++pass) {
      std::vector<int> rows;
      for (int i = 0; i < C.rows(); ++i) {
        if (pass == 1 &&
            std::find(interval.rows.begin(), interval.rows.end(), i) == interval.rows.end()) {
          continue;
        }
        const double slack = problem_.b()(i) - C.row(i).dot(lambda);
        bool touches_free = false;
        for (const int j : interval.free) touches_free = touches_free || C(i, j) > 0.0;
        if (touches_free && slack <= epsilon * C.row(i).maxCoeff()) rows.push_back(i);
      }
      interval.rows = rows;
      interval.basis.resize(static_cast<Eigen::Index>(interval.free.size()), 0);
      if (rows.empty()) return Eigen::VectorXd();
      interval.normals.resize(static_cast<Eigen::Index>(interval.free.size()),
                              static_cast<Eigen::Index>(rows.size()));
      for (std::size_t f = 0; f < interval.free.size(); ++f) {
        for (std::size_t r = 0; r < rows.size(); ++r) {
          interval.normals(static_cast<Eigen::Index>(f), static_cast<Eigen::Index>(r)) =
              C(rows[r], interval.free[f]);
        }
      }
      interval.qr.compute(interval.normals);
      const Eigen::VectorXd mu = -interval.qr.solve(gather(gradient, interval));
      if (pass == 1) {
        // The thin Q: the full one is |free| x |free|, and |free| is M at a dense iterate.
        interval.basis = interval.qr.householderQ() *
                         MatrixXd::Identity(interval.normals.rows(), interval.qr.rank());
        return mu;
      }
      std::vector<int> kept;
      for (std::size_t r = 0; r < rows.size(); ++r) {
        if (mu(static_cast<Eigen::Index>(r)) > 0.0) kept.push_back(rows[r]);
      }
      interval.rows = kept;
      if (kept.empty()) {
        interval.basis.resize(static_cast<Eigen::Index>(interval.free.size()), 0);
        return Eigen::VectorXd();
      }
    }
    return Eigen::VectorXd();
  }

  Interval bind(int k, const MatrixXd& x, const MatrixXd& gradient,
                const MatrixXd& gradient_point, double epsilon) {
    const Eigen::VectorXd lambda = x.row(k).transpose();
    Interval interval;
    interval.k = k;
    std::vector<int> near_zero;
    for (const int j : problem_.inService()) {
      const bool candidate = lambda(j) <= epsilon || gradient_point(k, j) <= 0.0;
      (candidate ? near_zero : interval.free).push_back(j);
    }
    // Multipliers from the clearly free rates decide which near-zero rates bind.
    const Eigen::VectorXd mu = bindRows(interval, lambda, gradient, epsilon);
    std::vector<int> held;
    for (const int j : near_zero) {
      double reduced = gradient(k, j);
      for (std::size_t r = 0; r < interval.rows.size(); ++r) {
        reduced += mu(static_cast<Eigen::Index>(r)) * problem_.C()(interval.rows[r], j);
      }
      if (reduced > 0.0) {
        held.push_back(j);
        zero_pushes_.push_back({k, j, reduced});
      } else {
        interval.free.push_back(j);
      }
    }
    std::sort(interval.free.begin(), interval.free.end());
    (void)bindRows(interval, lambda, gradient, epsilon);
    return interval;
  }

  const PlanningProblem& problem_;
  std::vector<Push> zero_pushes_;  // a list, not an N x M matrix: faces are copied
  Eigen::Index free_count_ = 0;
  std::vector<Interval> intervals_;
};

// The L-BFGS inverse-Hessian approximation from the last kMemory steps (two-loop recursion),
// applied in the tangent space of the current face: the pairs are projected onto it first, so
// that gradient changes of rates held at zero (large, and irrelevant to the step) do not spoil
// the curvature estimates. Projected pairs are kept while the face stays the same. The initial
// matrix is γ Z D^-1 Z' (Z' the projection onto the face, D^-1 the given inverse diagonal, or
// the identity when none is given) with γ = <s, y> / <y, Z D^-1 Z' y> of the newest pair.
class LimitedMemoryInverse {
 public:
  explicit LimitedMemoryInverse(const PlanningProblem& problem) : problem_(problem) {}

  // The oldest pair's storage is reused once the memory is full (N x M each: fresh blocks
  // would be mapped and faulted in every iteration under a fixed mmap threshold).
  void add(const MatrixXd& s, const MatrixXd& y) {
    Pair pair{MatrixXd(), MatrixXd(), Eigen::VectorXd(), Eigen::VectorXd(), 0.0, false};
    if (static_cast<int>(pairs_.size()) >= kMemory) {
      pair.s_transposed = std::move(pairs_.front().s_transposed);
      pair.y_transposed = std::move(pairs_.front().y_transposed);
      pairs_.pop_front();
    }
    pair.s_transposed = s.transpose();
    pair.y_transposed = y.transpose();
    pairs_.push_back(std::move(pair));
  }

  // H v on the face (v and the result compact), or nothing when no pair has positive
  // curvature there.
  [[nodiscard]] std::optional<Eigen::VectorXd> apply(const BindingFace& face,
                                                     const Eigen::VectorXd& v,
                                                     const Eigen::VectorXd& inverse_diagonal) {
    const bool same_face = face_ && face_->sameTangentSpace(face);
    face_.emplace(face);
    std::vector<const Pair*> usable;
    for (Pair& pair : pairs_) {
      if (!pair.projected || !same_face) project(face, pair);
      if (pair.rho > 0.0) usable.push_back(&pair);
    }
    if (usable.empty()) return std::nullopt;
    Eigen::VectorXd q = v;
    std::vector<double> a(usable.size());
    for (std::size_t i = usable.size(); i-- > 0;) {
      a[i] = usable[i]->rho * usable[i]->face_s.dot(q);
      q -= a[i] * usable[i]->face_y;
    }
    const Pair& newest = *usable.back();
    if (inverse_diagonal.size() == q.size()) {
      Eigen::VectorXd scaled_y = inverse_diagonal.cwiseProduct(newest.face_y);
      face.toTangent(scaled_y);
      q = inverse_diagonal.cwiseProduct(q);
      face.toTangent(q);
      q *= 1.0 / (newest.rho * newest.face_y.dot(scaled_y));
    } else {
      q *= 1.0 / (newest.rho * newest.face_y.squaredNorm());
    }
    for (std::size_t i = 0; i < usable.size(); ++i) {
      const double beta = usable[i]->rho * usable[i]->face_y.dot(q);
      q += (a[i] - beta) * usable[i]->face_s;
    }
    return q;
  }

 private:
  struct Pair {
    MatrixXd s_transposed, y_transposed;  // as taken, M x N (compacting reads them by interval)
    Eigen::VectorXd face_s, face_y;  // projected onto the face, compact
    double rho;                      // 1 / <face_s, face_y>, or 0 when not positive
    bool projected;
  };

  static void project(const BindingFace& face, Pair& pair) {
    pair.face_s = face.compactOfTransposed(pair.s_transposed);
    pair.face_y = face.compactOfTransposed(pair.y_transposed);
    const double sy = pair.face_s.dot(pair.face_y);
    const double scale = pair.face_s.norm() * pair.face_y.norm();
    pair.rho = sy > 1e-12 * scale ? 1.0 / sy : 0.0;
    pair.projected = true;
  }

  const PlanningProblem& problem_;
  std::deque<Pair> pairs_;
  std::optional<BindingFace> face_;
};

// The gradient restricted to the variables (planned rows, sensors in service), in place.
MatrixXd masked(const PlanningProblem& problem, MatrixXd gradient) {
  gradient.topRows(problem.firstInterval()).setZero();
  std::vector<bool> in_service(static_cast<std::size_t>(gradient.cols()), false);
  for (const int j : problem.inService()) in_service[static_cast<std::size_t>(j)] = true;
  for (Eigen::Index j = 0; j < gradient.cols(); ++j) {
    if (!in_service[static_cast<std::size_t>(j)]) gradient.col(j).setZero();
  }
  return gradient;
}

struct Iterate {
  MatrixXd x;
  double cost = 0.0;
  MatrixXd gradient;  // masked
};

class ProjectedQuasiNewton {
 public:
  ProjectedQuasiNewton(PlanningProblem& problem, const PlanRequest& request,
                       Clock::time_point start)
      : problem_(problem), request_(request), start_(start), memory_(problem) {}

  PlanningOutcome run() {
    current_ = evaluate(problem_.rates());
    if (!std::isfinite(current_.cost)) {
      return {0, PlanStatus::Failed, 0, "no finite cost at the start point"};
    }
    const double unit = problem_.rateUnit();
    sigma_ = unit * unit / costUnit(current_.cost);
    const double first = problem_.largestChange(
        current_.x, problem_.projected(current_.x - sigma_ * current_.gradient));
    if (first > 0.0) alpha_ = std::clamp(1.0 / first, kMinScaledStep, kMaxScaledStep);
    for (int iteration = 0;; ++iteration) {
      problem_.setRates(current_.x);
      const double residual =
          projectedGradientResidual(problem_, current_.x, {current_.cost, current_.gradient});
      if (residual <= request_.tolerance) return {iteration, PlanStatus::Optimal};
      if (iteration >= request_.max_iterations) return {iteration, PlanStatus::MaxIterations};
      const double elapsed = secondsSince(start_);
      if (elapsed > request_.max_seconds) return {iteration, PlanStatus::TimeLimit};
      if (request_.progress && !request_.progress({iteration, current_.cost, elapsed})) {
        return {iteration, PlanStatus::Stopped};
      }
      std::optional<Iterate> next = quasiNewtonStep(std::min(kMaxActiveWidth, residual) * unit);
      if (!next) next = projectedGradientStep();
      if (!next) return {iteration, PlanStatus::Stalled};
      const MatrixXd s = next->x - current_.x;
      const MatrixXd y = next->gradient - current_.gradient;
      const double sy = problem_.inner(s, y);
      alpha_ = sy > 0.0 ? std::clamp(problem_.inner(s, s) / (sigma_ * sy), kMinScaledStep,
                                     kMaxScaledStep)
                        : kMaxScaledStep;
      memory_.add(s, y);
      current_ = std::move(*next);
    }
  }

  [[nodiscard]] int evaluations() const { return evaluations_; }

 private:
  Iterate evaluate(const MatrixXd& x) {
    ++evaluations_;
    CostGradient cg = problem_.transcription().costAndGradient(x);
    return {x, cg.cost, masked(problem_, std::move(cg.gradient))};
  }

  // L-BFGS in the tangent space of the binding face, rates held at zero sent there, searched
  // along the projection arc. Nothing when the arc does not descend. The face is identified by
  // the projected gradient step of the KKT residual (scaled step 1): a rate that step sends to
  // zero is held if its reduced gradient is positive, however large it is now, so that the
  // many rates of a dense start that end at zero leave together rather than a few per
  // iteration; the rate they give up goes to the free rates of a binding row.
  std::optional<Iterate> quasiNewtonStep(double epsilon) {
    const MatrixXd gradient_point = problem_.projected(current_.x - sigma_ * current_.gradient);
    const BindingFace face(problem_, current_.x, current_.gradient, gradient_point, epsilon);
    const Eigen::VectorXd v = face.compact(current_.gradient);
    const std::optional<Eigen::VectorXd> hv = memory_.apply(face, v, inverseDiagonal(face));
    MatrixXd direction = face.expand(hv ? Eigen::VectorXd(-*hv) : Eigen::VectorXd(-(alpha_ * sigma_) * v));
    for (const BindingFace::Push& push : face.zeroPushes()) {
      direction(push.k, push.j) = -std::max(current_.x(push.k, push.j), sigma_ * push.reduced);
    }
    face.moveOntoBindingRows(current_.x, direction);
    return arcSearch(direction);
  }

  // For the information form, the inverse of a diagonal estimate of the Hessian on the free
  // rates, up to a scale: ∂²J/∂λ_kj² ≈ 2 |g_kj| h̃_j' P h̃_j for a rank-one S_j = h̃_j h̃_j'
  // (the second derivative of <W, (Y + λ S_j)^-1>), with the covariance P replaced by the
  // identity: tr S_j |g_kj|. (With P at the interval's start it took more iterations: n = 50,
  // M = 1000: 281 against 249.) Empty for the covariance form, where it did not help (n = 20,
  // M = 30: 133-234 iterations against 114-159).
  [[nodiscard]] Eigen::VectorXd inverseDiagonal(const BindingFace& face) const {
    if (problem_.transcription().form() != SurrogateForm::Information) return Eigen::VectorXd();
    const Eigen::VectorXd& information = problem_.sensorInformation();
    const Eigen::VectorXd diagonal = face.gatherOf([&](int k, int j) {
      return information(j) * std::abs(current_.gradient(k, j));
    });
    if (diagonal.size() == 0) return diagonal;
    const double floor = 1e-12 * diagonal.maxCoeff();
    if (!(floor > 0.0)) return Eigen::VectorXd();
    return diagonal.cwiseMax(floor).cwiseInverse();
  }

  // A spectral projected gradient step, searched along the segment to the projected point.
  // Its direction descends whenever the projection is exact; the projection under energy
  // budgets is iterative and may stop short for a point very far outside (a spectral step of
  // kMaxScaledStep after a step of negative curvature), so a step that does not descend is
  // tried again 100 times shorter, a few times.
  std::optional<Iterate> projectedGradientStep() {
    MatrixXd direction;
    double slope = 0.0;
    for (double alpha = alpha_;; alpha = std::max(kMinScaledStep, 0.01 * alpha)) {
      direction =
          problem_.projected(current_.x - (alpha * sigma_) * current_.gradient) - current_.x;
      slope = problem_.inner(current_.gradient, direction);
      if (slope < 0.0) break;
      if (alpha <= kMinScaledStep || alpha < 1e-12 * alpha_) return std::nullopt;
    }
    double t = 1.0;
    for (int i = 0; i < kMaxBacktracks; ++i) {
      Iterate trial = evaluate(current_.x + t * direction);
      if (trial.cost <= current_.cost + kSufficientDecrease * t * slope) return trial;
      t = interpolatedStep(t, slope, trial.cost);
    }
    return std::nullopt;
  }

  // Along the arc, a long step may bend by projection into a direction that does not descend
  // (rates clipped at zero, rows clipped at their bound), while a shorter one does: such steps
  // are shortened tenfold without evaluating the cost (the projection is cheap), and only a
  // step with negative slope is evaluated.
  std::optional<Iterate> arcSearch(const MatrixXd& direction) {
    double t = 1.0;
    int shortenings = 0;
    for (int i = 0; i < kMaxBacktracks;) {
      const MatrixXd x = problem_.projected(current_.x + t * direction);
      const double slope = problem_.inner(current_.gradient, x - current_.x);
      if (!(slope < 0.0)) {
        if (++shortenings > kMaxShortenings) return std::nullopt;
        t *= 0.1;
        continue;
      }
      ++i;
      Iterate trial = evaluate(x);
      if (trial.cost <= current_.cost + kSufficientDecrease * slope) return trial;
      // slope already carries the step; interpolate as if along a segment of length t.
      t = interpolatedStep(t, slope / t, trial.cost);
    }
    return std::nullopt;
  }

  // The minimizer of the quadratic through f(0), f'(0) = slope and f(t), kept in
  // [0.1 t, 0.5 t] (bisection when the cost is not finite).
  [[nodiscard]] double interpolatedStep(double t, double slope, double cost) const {
    if (!std::isfinite(cost)) return 0.5 * t;
    const double curvature = cost - current_.cost - t * slope;
    const double next = curvature > 0.0 ? -0.5 * t * t * slope / curvature : 0.5 * t;
    return std::clamp(next, 0.1 * t, 0.5 * t);
  }

  PlanningProblem& problem_;
  const PlanRequest& request_;
  Clock::time_point start_;
  LimitedMemoryInverse memory_;
  Iterate current_;
  double sigma_ = 1.0;  // scaled step -> rate step: rateUnit² / |J(start)|
  double alpha_ = 1.0;  // spectral (Barzilai-Borwein) step in scaled units

  int evaluations_ = 0;
};

}  // namespace

PlanningOutcome solveWithProjectedQuasiNewton(PlanningProblem& problem,
                                              const PlanRequest& request,
                                              Clock::time_point start) {
  ProjectedQuasiNewton solver(problem, request, start);
  PlanningOutcome outcome = solver.run();
  outcome.evaluations = solver.evaluations();
  return outcome;
}

}  // namespace sensornet::planning
