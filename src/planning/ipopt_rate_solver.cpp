#include <IpIpoptApplication.hpp>
#include <IpTNLP.hpp>
#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "planning_problem.hpp"

namespace sensornet::planning {
namespace {

// The NLP handed to IPOPT: min J(λ) over the planned rates, 0 <= λ_kj <= λ̄_j (implied by the
// constraints, stated to help the interior-point method), C λ_k <= b for every planned
// interval, then Σ_k h λ_kj <= E_j left for every sensor in service with an energy budget:
// linear, so the Jacobian is constant. The Hessian is left to IPOPT's L-BFGS.
class RateProgram : public Ipopt::TNLP {
 public:
  RateProgram(PlanningProblem& problem, const PlanRequest& request, Clock::time_point start)
      : problem_(problem), request_(request), start_(start), rates_(problem.rates()) {
    const auto& C = problem_.C();
    for (Eigen::Index i = 0; i < C.rows(); ++i) {
      std::vector<std::pair<int, double>> row;
      for (std::size_t f = 0; f < problem_.inService().size(); ++f) {
        const double c = C(i, problem_.inService()[f]);
        if (c > 0.0) row.emplace_back(static_cast<int>(f), c);
      }
      if (!row.empty()) {
        rows_.push_back(std::move(row));
        bounds_.push_back(problem_.b()(i));
      }
    }
    max_rates_ = problem_.polytope().maxRates();
    const Eigen::VectorXd& energy = problem_.energyLeft();
    for (std::size_t f = 0; f < problem_.inService().size() && energy.size() > 0; ++f) {
      const int j = problem_.inService()[f];
      if (energy(j) < std::numeric_limits<double>::infinity()) {
        budgeted_.emplace_back(static_cast<int>(f), energy(j));
        max_rates_(j) = std::min(max_rates_(j), energy(j) / problem_.intervalLength());
      }
    }
  }

  bool get_nlp_info(Ipopt::Index& n, Ipopt::Index& m, Ipopt::Index& nnz_jac_g,
                    Ipopt::Index& nnz_h_lag, IndexStyleEnum& index_style) override {
    n = problem_.variables();
    m = intervalRows() + static_cast<int>(budgeted_.size());
    int per_interval = 0;
    for (const auto& row : rows_) per_interval += static_cast<int>(row.size());
    nnz_jac_g = problem_.plannedIntervals() * (per_interval + static_cast<int>(budgeted_.size()));
    nnz_h_lag = 0;
    index_style = C_STYLE;
    return true;
  }

  bool get_bounds_info(Ipopt::Index n, Ipopt::Number* x_l, Ipopt::Number* x_u, Ipopt::Index m,
                       Ipopt::Number* g_l, Ipopt::Number* g_u) override {
    const auto in_service = problem_.inService().size();
    for (Ipopt::Index i = 0; i < n; ++i) {
      x_l[i] = 0.0;
      x_u[i] = max_rates_(problem_.inService()[static_cast<std::size_t>(i) % in_service]);
    }
    for (Ipopt::Index c = 0; c < m; ++c) {
      g_l[c] = -2e19;
      g_u[c] = c < intervalRows() ? bounds_[static_cast<std::size_t>(c) % rows_.size()]
                                  : budgeted_[static_cast<std::size_t>(c - intervalRows())].second;
    }
    return true;
  }

  bool get_starting_point(Ipopt::Index, bool init_x, Ipopt::Number* x, bool, Ipopt::Number*,
                          Ipopt::Number*, Ipopt::Index, bool, Ipopt::Number*) override {
    if (init_x) getVariables(x);
    return true;
  }

  bool eval_f(Ipopt::Index, const Ipopt::Number* x, bool new_x,
              Ipopt::Number& obj_value) override {
    if (new_x || !cached_) evaluate(x);
    obj_value = cached_cost_;
    return std::isfinite(cached_cost_);
  }

  bool eval_grad_f(Ipopt::Index, const Ipopt::Number* x, bool new_x,
                   Ipopt::Number* grad_f) override {
    if (new_x || !cached_) evaluate(x);
    if (!std::isfinite(cached_cost_)) return false;
    gather(cached_gradient_, grad_f);
    return true;
  }

  // new_x is about the last call of ANY evaluation: eval_g(x, true) may be followed by
  // eval_f(x, false), so every callback invalidates the cached objective.
  bool eval_g(Ipopt::Index, const Ipopt::Number* x, bool new_x, Ipopt::Index,
              Ipopt::Number* g) override {
    if (new_x) cached_ = false;
    const std::size_t width = problem_.inService().size();
    std::size_t c = 0;
    for (int k = 0; k < problem_.plannedIntervals(); ++k) {
      const Ipopt::Number* xk = x + static_cast<std::size_t>(k) * width;
      for (const auto& row : rows_) {
        double load = 0.0;
        for (const auto& [f, coefficient] : row) load += coefficient * xk[f];
        g[c++] = load;
      }
    }
    for (const auto& [f, budget] : budgeted_) {
      double used = 0.0;
      for (int k = 0; k < problem_.plannedIntervals(); ++k) {
        used += problem_.intervalLength() *
                x[static_cast<std::size_t>(k) * width + static_cast<std::size_t>(f)];
      }
      g[c++] = used;
    }
    return true;
  }

  bool eval_jac_g(Ipopt::Index, const Ipopt::Number*, bool new_x, Ipopt::Index, Ipopt::Index,
                  Ipopt::Index* iRow, Ipopt::Index* jCol, Ipopt::Number* values) override {
    if (new_x) cached_ = false;
    const int width = static_cast<int>(problem_.inService().size());
    std::size_t e = 0;
    int c = 0;
    for (int k = 0; k < problem_.plannedIntervals(); ++k) {
      for (const auto& row : rows_) {
        for (const auto& [f, coefficient] : row) {
          if (values == nullptr) {
            iRow[e] = c;
            jCol[e] = k * width + f;
          } else {
            values[e] = coefficient;
          }
          ++e;
        }
        ++c;
      }
    }
    for (const auto& budgeted : budgeted_) {
      for (int k = 0; k < problem_.plannedIntervals(); ++k) {
        if (values == nullptr) {
          iRow[e] = c;
          jCol[e] = k * width + budgeted.first;
        } else {
          values[e] = problem_.intervalLength();
        }
        ++e;
      }
      ++c;
    }
    return true;
  }

  bool intermediate_callback(Ipopt::AlgorithmMode, Ipopt::Index iter, Ipopt::Number obj_value,
                             Ipopt::Number, Ipopt::Number, Ipopt::Number, Ipopt::Number,
                             Ipopt::Number, Ipopt::Number, Ipopt::Number, Ipopt::Index,
                             const Ipopt::IpoptData*, Ipopt::IpoptCalculatedQuantities*) override {
    iterations_ = iter;
    const double elapsed = secondsSince(start_);
    if (elapsed > request_.max_seconds) {
      stop_reason_ = PlanStatus::TimeLimit;
      return false;
    }
    if (request_.progress && !request_.progress({iter, obj_value, elapsed})) {
      stop_reason_ = PlanStatus::Stopped;
      return false;
    }
    return true;
  }

  void finalize_solution(Ipopt::SolverReturn status, Ipopt::Index, const Ipopt::Number* x,
                         const Ipopt::Number*, const Ipopt::Number*, Ipopt::Index,
                         const Ipopt::Number*, const Ipopt::Number*, Ipopt::Number,
                         const Ipopt::IpoptData*, Ipopt::IpoptCalculatedQuantities*) override {
    status_ = status;
    if (x != nullptr) {
      setVariables(x);
      problem_.setRates(rates_);
    }
  }

  [[nodiscard]] int iterations() const { return iterations_; }
  [[nodiscard]] int evaluations() const { return evaluations_; }
  [[nodiscard]] PlanStatus status() const {
    switch (status_) {
      case Ipopt::SUCCESS:
        return PlanStatus::Optimal;
      case Ipopt::STOP_AT_ACCEPTABLE_POINT:
        return PlanStatus::Acceptable;
      case Ipopt::MAXITER_EXCEEDED:
        return PlanStatus::MaxIterations;
      case Ipopt::CPUTIME_EXCEEDED:
        return PlanStatus::TimeLimit;
      case Ipopt::USER_REQUESTED_STOP:
        return stop_reason_;
      default:
        return PlanStatus::Failed;
    }
  }
  // Why a Failed solve failed (empty otherwise).
  [[nodiscard]] std::string failure() const {
    return status() == PlanStatus::Failed ? describeFailure(status_) : std::string();
  }

 private:
  static std::string describeFailure(Ipopt::SolverReturn status) {
    switch (status) {
      case Ipopt::STOP_AT_TINY_STEP:
        return "search direction became too small";
      case Ipopt::LOCAL_INFEASIBILITY:
        return "locally infeasible";
      case Ipopt::DIVERGING_ITERATES:
        return "diverging iterates";
      case Ipopt::RESTORATION_FAILURE:
        return "restoration phase failed";
      case Ipopt::ERROR_IN_STEP_COMPUTATION:
        return "error in step computation";
      case Ipopt::INVALID_NUMBER_DETECTED:
        return "invalid number detected";
      default:
        return "IPOPT status " + std::to_string(static_cast<int>(status));
    }
  }

  [[nodiscard]] int intervalRows() const {
    return problem_.plannedIntervals() * static_cast<int>(rows_.size());
  }

  // x is interval-major over the planned intervals and the sensors in service.
  void setVariables(const Ipopt::Number* x) {
    std::size_t i = 0;
    for (int k = problem_.firstInterval(); k < problem_.intervals(); ++k) {
      for (const int j : problem_.inService()) rates_(k, j) = x[i++];
    }
  }
  void getVariables(Ipopt::Number* x) const { gather(rates_, x); }
  void gather(const Eigen::MatrixXd& matrix, Ipopt::Number* x) const {
    std::size_t i = 0;
    for (int k = problem_.firstInterval(); k < problem_.intervals(); ++k) {
      for (const int j : problem_.inService()) x[i++] = matrix(k, j);
    }
  }

  void evaluate(const Ipopt::Number* x) {
    setVariables(x);
    ++evaluations_;
    CostGradient cg = problem_.transcription().costAndGradient(rates_);
    cached_cost_ = cg.cost;
    cached_gradient_ = std::move(cg.gradient);
    cached_ = true;
  }

  PlanningProblem& problem_;
  const PlanRequest& request_;
  Clock::time_point start_;
  Eigen::MatrixXd rates_;
  std::vector<std::vector<std::pair<int, double>>> rows_;  // C restricted to sensors in service
  std::vector<double> bounds_;
  std::vector<std::pair<int, double>> budgeted_;  // (index among those in service, energy left)
  Eigen::VectorXd max_rates_;
  bool cached_ = false;
  double cached_cost_ = 0.0;
  Eigen::MatrixXd cached_gradient_;
  int iterations_ = 0;
  int evaluations_ = 0;
  Ipopt::SolverReturn status_ = Ipopt::UNASSIGNED;
  PlanStatus stop_reason_ = PlanStatus::Stopped;  // of a USER_REQUESTED_STOP
};

// IPOPT with MUMPS (Debian's sequential build) is not known to be reentrant: one solve at a time
// in this process.
std::mutex& ipoptMutex() {
  static std::mutex mutex;
  return mutex;
}

}  // namespace

PlanningOutcome solveWithIpopt(PlanningProblem& problem, const PlanRequest& request,
                               Clock::time_point start) {
  const double cost_scale = 1.0 / costUnit(problem.transcription().cost(problem.rates()));
  Ipopt::SmartPtr<RateProgram> program = new RateProgram(problem, request, start);
  Ipopt::SmartPtr<Ipopt::IpoptApplication> app = IpoptApplicationFactory();
  auto& options = *app->Options();
  options.SetIntegerValue("print_level", 0);
  options.SetStringValue("sb", "yes");
  options.SetStringValue("hessian_approximation", "limited-memory");
  options.SetStringValue("jac_c_constant", "yes");
  options.SetStringValue("jac_d_constant", "yes");
  options.SetNumericValue("tol", request.tolerance);
  options.SetIntegerValue("max_iter", request.max_iterations);
  options.SetNumericValue("obj_scaling_factor", cost_scale);
  options.SetStringValue("nlp_scaling_method", "none");
  std::lock_guard<std::mutex> lock(ipoptMutex());
  if (app->Initialize() != Ipopt::Solve_Succeeded) {
    throw std::runtime_error("planner: IPOPT failed to initialize");
  }
  app->OptimizeTNLP(program);
  return {program->iterations(), program->status(), program->evaluations(), program->failure()};
}

}  // namespace sensornet::planning
