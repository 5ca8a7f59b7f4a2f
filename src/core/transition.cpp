#include "sensornet/core/transition.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <complex>
#include <limits>
#include <optional>
#include <string>
#include <type_traits>
#include <utility>
#include <unsupported/Eigen/MatrixFunctions>
#include <vector>

#include "sensornet/core/input_error.hpp"

namespace sensornet {
namespace {

constexpr const char* kSource = "LtiTransition";

// A = V Λ V^{-1} with the constant parts of Qd and G carried into the eigenbasis:
//   Qd = V [Q̃_ij ∫_0^dt e^{μ_ij s} ds] V',        Q̃ = V^{-1} Q V^{-T}
//   G  = V^{-T} [W̃_ij ∫_0^dt e^{μ_ij s} ds] V^{-1}, W̃ = V' W V
// with μ_ij = λ_i + λ_j. Plain transposes throughout (not conjugate): for complex V, Q̃ and W̃
// are complex symmetric.
//
// With complex eigenvalues the O(n³) products still run in real arithmetic: V = T C, where T
// is real (a real eigenvector, or Re v and Im v of a conjugate pair (v, v̄)) and C is block
// diagonal with blocks [1] or [[1, 1], [i, -i]]. Then V X V' = T (C X C') T' and
// V^{-T} Y V^{-1} = T^{-T} (C^{-T} Y C^{-1}) T^{-1}, and the inner factors are real and cost
// O(n²). For Scalar = double there are no pairs and C = I.
template <typename Scalar>
struct ModalForm {
  using Matrix = Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>;
  using Vector = Eigen::Matrix<Scalar, Eigen::Dynamic, 1>;
  Vector eigenvalues;               // a conjugate pair occupies (j, j+1), imag(λ_j) > 0 or < 0
  std::vector<Eigen::Index> pairs;  // first index j of every conjugate pair
  Eigen::MatrixXd T;
  Eigen::MatrixXd T_inv;
  Matrix Q_modal;                                              // Q̃
  Matrix W_modal;                                              // W̃
  Matrix WQ_modal;                                             // W̃ ∘ Q̃ (elementwise)
  double condition = std::numeric_limits<double>::infinity();  // cond_2(T) = cond_2(V)
  bool diagonalizes = false;  // A V = V Λ to rounding, V invertible
};

// Builds the modal form from Eigen's eigen-decomposition, rebuilding V = T C so that the
// conjugate structure the real-arithmetic products rely on holds exactly.
template <typename Scalar>
ModalForm<Scalar> makeModalForm(const Eigen::MatrixXd& A, const Eigen::VectorXcd& eigenvalues,
                                const Eigen::MatrixXcd& V, const Eigen::MatrixXd& Q,
                                const Eigen::MatrixXd& W) {
  using Complex = std::complex<double>;
  const Eigen::Index n = eigenvalues.size();
  ModalForm<Scalar> form;
  Eigen::VectorXcd lambda = eigenvalues;
  form.T.resize(n, n);
  Eigen::MatrixXcd C = Eigen::MatrixXcd::Identity(n, n);
  for (Eigen::Index j = 0; j < n; ++j) {
    if (eigenvalues(j).imag() == 0.0 || j + 1 == n) {
      form.T.col(j) = V.col(j).real();
      continue;
    }
    form.pairs.push_back(j);
    lambda(j + 1) = std::conj(lambda(j));
    form.T.col(j) = V.col(j).real();
    form.T.col(j + 1) = V.col(j).imag();
    C(j + 1, j) = Complex(0.0, 1.0);
    C(j, j + 1) = 1.0;
    C(j + 1, j + 1) = Complex(0.0, -1.0);
    ++j;
  }
  // C is √2 times a unitary on each pair, so cond(V) = cond(T) for unit-norm v.
  const Eigen::VectorXd sigma = Eigen::JacobiSVD<Eigen::MatrixXd>(form.T).singularValues();
  if (!form.T.allFinite() || !(sigma(n - 1) > 0.0)) return form;
  form.condition = sigma(0) / sigma(n - 1);
  form.T_inv = form.T.fullPivLu().inverse();
  const Eigen::MatrixXcd Vc = form.T.template cast<Complex>() * C;
  const Eigen::MatrixXcd Vc_inv = C.inverse() * form.T_inv.template cast<Complex>();
  const Eigen::MatrixXcd Q_modal = Vc_inv * Q.cast<Complex>() * Vc_inv.transpose();
  const Eigen::MatrixXcd W_modal = Vc.transpose() * W.cast<Complex>() * Vc;
  // Eigen may report a complex pair with a tiny imaginary part as two real eigenvalues with
  // pseudo-eigenvectors; only trust the basis when it really diagonalizes A.
  const double residual = (A.cast<Complex>() * Vc - Vc * lambda.asDiagonal()).norm();
  form.diagonalizes = residual <= 1e-12 * std::max(A.norm(), std::numeric_limits<double>::min());
  if constexpr (std::is_same_v<Scalar, double>) {
    form.eigenvalues = lambda.real();
    form.Q_modal = Q_modal.real();
    form.W_modal = W_modal.real();
  } else {
    form.eigenvalues = lambda;
    form.Q_modal = Q_modal;
    form.W_modal = W_modal;
  }
  form.WQ_modal = form.W_modal.cwiseProduct(form.Q_modal);
  return form;
}

// Complex products and quotients written out: the std::complex operators carry C99 Annex G
// NaN/infinity recovery that costs a library call in the inner loop.
inline double times(double a, double b) { return a * b; }
inline std::complex<double> times(std::complex<double> a, std::complex<double> b) {
  return {a.real() * b.real() - a.imag() * b.imag(), a.real() * b.imag() + a.imag() * b.real()};
}
inline double dividedBy(double a, double b) { return a / b; }
inline std::complex<double> dividedBy(std::complex<double> a, std::complex<double> b) {
  const double scale = 1.0 / (b.real() * b.real() + b.imag() * b.imag());
  return times(a, std::conj(b)) * scale;
}
inline double squaredModulus(double a) { return a * a; }
inline double squaredModulus(std::complex<double> a) {
  return a.real() * a.real() + a.imag() * a.imag();
}

// Taylor coefficients of φ2(z) = (e^z - 1 - z)/z² = Σ_k z^k/(k+2)!. Below |z| = 0.5 the 14
// terms leave a truncation error under 3e-18 relative.
constexpr double kSeriesRadius = 0.5;
constexpr int kSeriesTerms = 14;
constexpr std::array<double, kSeriesTerms> phi2Coefficients() {
  std::array<double, kSeriesTerms> c{};
  double factorial = 2.0;  // (k+2)! at k = 0
  for (int k = 0; k < kSeriesTerms; ++k) {
    c[static_cast<std::size_t>(k)] = 1.0 / factorial;
    factorial *= static_cast<double>(k + 3);
  }
  return c;
}
constexpr std::array<double, kSeriesTerms> kPhi2Coefficients = phi2Coefficients();

// The two scalar integrals an entry of the eigenbasis needs, for z = μ dt:
//   φ1(z) = (e^z - 1)/z     (∫_0^dt e^{μs} ds = dt φ1),
//   φ2(z) = (e^z - 1 - z)/z² (∫_0^dt ∫_0^s e^{μr} dr ds = dt² φ2).
// Small |z| by series (the closed forms cancel there); otherwise from exp_z = e^z, which the
// caller forms as a product e^{λ_i dt} e^{λ_j dt} so that a call needs only n exponentials.
template <typename Scalar>
void evaluatePhi(Scalar z, Scalar exp_z, Scalar& phi1, Scalar& phi2) {
  if (squaredModulus(z) < kSeriesRadius * kSeriesRadius) {
    Scalar p = Scalar(kPhi2Coefficients[kSeriesTerms - 1]);
    for (int k = kSeriesTerms - 2; k >= 0; --k) {
      p = times(p, z) + Scalar(kPhi2Coefficients[static_cast<std::size_t>(k)]);
    }
    phi2 = p;
    phi1 = Scalar(1.0) + times(z, p);
  } else {
    const Scalar em1 = exp_z - Scalar(1.0);
    phi1 = dividedBy(em1, z);
    phi2 = dividedBy(em1 - z, times(z, z));
  }
}

// For every conjugate pair (j, j+1), rows j, j+1 of M become (s (r_j + r_{j+1}),
// ±s i (r_j - r_{j+1})): C M for (s, +), C^{-T} M for (1/2, -). By symmetry the same map on
// columns is M C' and M C^{-1}.
void mixPairRows(Eigen::MatrixXcd& M, const std::vector<Eigen::Index>& pairs, double s,
                 double sign) {
  for (const Eigen::Index j : pairs) {
    for (Eigen::Index c = 0; c < M.cols(); ++c) {
      const std::complex<double> a = M(j, c);
      const std::complex<double> b = M(j + 1, c);
      const std::complex<double> d = a - b;
      M(j, c) = s * (a + b);
      M(j + 1, c) = (sign * s) * std::complex<double>(-d.imag(), d.real());
    }
  }
}
void mixPairColumns(Eigen::MatrixXcd& M, const std::vector<Eigen::Index>& pairs, double s,
                    double sign) {
  for (const Eigen::Index j : pairs) {
    for (Eigen::Index r = 0; r < M.rows(); ++r) {
      const std::complex<double> a = M(r, j);
      const std::complex<double> b = M(r, j + 1);
      const std::complex<double> d = a - b;
      M(r, j) = s * (a + b);
      M(r, j + 1) = (sign * s) * std::complex<double>(-d.imag(), d.real());
    }
  }
}

// C X C' (s = 1, +) or C^{-T} X C^{-1} (s = 1/2, -), whose result is real.
Eigen::MatrixXd realInnerFactor(const Eigen::MatrixXd& X, const std::vector<Eigen::Index>&, double,
                                double) {
  return X;
}
Eigen::MatrixXd realInnerFactor(Eigen::MatrixXcd X, const std::vector<Eigen::Index>& pairs,
                                double s, double sign) {
  mixPairRows(X, pairs, s, sign);
  mixPairColumns(X, pairs, s, sign);
  return X.real();
}

template <typename Scalar>
void overModal(const ModalForm<Scalar>& form, double dt, IntervalTransition& step) {
  using Matrix = typename ModalForm<Scalar>::Matrix;
  using Vector = typename ModalForm<Scalar>::Vector;
  const Eigen::Index n = form.eigenvalues.size();
  const Vector z = form.eigenvalues * dt;
  const Vector e = z.array().exp();

  Matrix qd_modal(n, n);
  Matrix g_modal(n, n);
  Scalar noise(0.0);
  const double dt2 = dt * dt;
  for (Eigen::Index j = 0; j < n; ++j) {
    for (Eigen::Index i = j; i < n; ++i) {
      Scalar phi1(0.0);
      Scalar phi2(0.0);
      evaluatePhi<Scalar>(z(i) + z(j), times(e(i), e(j)), phi1, phi2);
      const Scalar q = times(form.Q_modal(i, j), dt * phi1);
      const Scalar w = times(form.W_modal(i, j), dt * phi1);
      qd_modal(i, j) = q;
      qd_modal(j, i) = q;
      g_modal(i, j) = w;
      g_modal(j, i) = w;
      // <W, Qd(s)>_F = Σ_ij W̃_ij Q̃_ij dt φ1(μ_ij s), integrated over s in [0, dt].
      const Scalar c = times(form.WQ_modal(i, j), dt2 * phi2);
      noise += (i == j) ? c : 2.0 * c;
    }
  }

  // e^{A dt} = T (C e^{Λ dt} C^{-1}) T^{-1}; the inner factor has the real 2 x 2 block
  // [[Re e, Im e], [-Im e, Re e]] for a pair, e = e^{λ_j dt}.
  Eigen::MatrixXd T_scaled = form.T;
  if constexpr (std::is_same_v<Scalar, double>) {
    T_scaled = T_scaled * e.asDiagonal();
  } else {
    std::vector<bool> in_pair(static_cast<std::size_t>(n), false);
    for (const Eigen::Index j : form.pairs) {
      in_pair[static_cast<std::size_t>(j)] = in_pair[static_cast<std::size_t>(j + 1)] = true;
      const double re = e(j).real();
      const double im = e(j).imag();
      T_scaled.col(j) = re * form.T.col(j) - im * form.T.col(j + 1);
      T_scaled.col(j + 1) = im * form.T.col(j) + re * form.T.col(j + 1);
    }
    for (Eigen::Index j = 0; j < n; ++j) {
      if (!in_pair[static_cast<std::size_t>(j)]) T_scaled.col(j) *= e(j).real();
    }
  }
  step.Phi.noalias() = T_scaled * form.T_inv;

  const Eigen::MatrixXd qd_inner = realInnerFactor(qd_modal, form.pairs, 1.0, 1.0);
  const Eigen::MatrixXd g_inner = realInnerFactor(g_modal, form.pairs, 0.5, -1.0);
  step.Qd.noalias() = form.T * qd_inner * form.T.transpose();
  step.cost_gramian.noalias() = form.T_inv.transpose() * g_inner * form.T_inv;
  if constexpr (std::is_same_v<Scalar, double>) {
    step.noise_cost = noise;
  } else {
    step.noise_cost = noise.real();
  }
}

// Nilpotent A (A^m = 0 exactly as computed; integrator chains such as the double integrator):
// e^{As} = Σ_{k<m} A^k s^k / k! and every Taylor series below terminates, so
//   Phi        = Σ_{k<m}    A^k dt^k / k!
//   Qd         = Σ_{k<2m-1} L^k(Q) dt^{k+1} / (k+1)!,    L(X) = A X + X A'
//   G          = Σ_{k<2m-1} L'^k(W) dt^{k+1} / (k+1)!,   L'(X) = A' X + X A
//   noise_cost = Σ_{k<2m-1} <W, L^k(Q)> dt^{k+2} / (k+2)!
// with L^k(Q) = Σ_j C(k, j) A^j Q A'^{k-j}, whose terms with j >= m or k - j >= m vanish.
// Exact polynomials in dt with coefficients fixed by (A, Q, W).
struct PolynomialForm {
  std::vector<Eigen::MatrixXd> phi;  // coefficient of dt^k
  std::vector<Eigen::MatrixXd> qd;   // coefficient of dt^{k+1}
  std::vector<Eigen::MatrixXd> g;    // coefficient of dt^{k+1}
  std::vector<double> noise;         // coefficient of dt^{k+2}
};

std::optional<PolynomialForm> makePolynomialForm(const Eigen::MatrixXd& A, const Eigen::MatrixXd& Q,
                                                 const Eigen::MatrixXd& W) {
  const Eigen::Index n = A.rows();
  std::vector<Eigen::MatrixXd> powers = {Eigen::MatrixXd::Identity(n, n)};
  bool nilpotent = false;
  for (Eigen::Index p = 1; p <= n; ++p) {
    Eigen::MatrixXd next = powers.back() * A;
    if ((next.array() == 0.0).all()) {
      nilpotent = true;
      break;
    }
    powers.push_back(std::move(next));
  }
  if (!nilpotent) return std::nullopt;

  const int m = static_cast<int>(powers.size());  // A^m = 0
  PolynomialForm form;
  double factorial = 1.0;  // k!
  for (int k = 0; k < m; ++k) {
    if (k > 0) factorial *= k;
    form.phi.push_back(powers[static_cast<std::size_t>(k)] / factorial);
  }
  double factorial_next = 1.0;  // (k+1)!
  for (int k = 0; k <= 2 * m - 2; ++k) {
    if (k > 0) factorial_next *= k + 1;
    Eigen::MatrixXd LQ = Eigen::MatrixXd::Zero(n, n);
    Eigen::MatrixXd LW = Eigen::MatrixXd::Zero(n, n);
    double binomial = 1.0;  // C(k, j), updated as j runs from 0
    for (int j = 0; j <= k; ++j) {
      if (j > 0) binomial = binomial * (k - j + 1) / j;
      if (j >= m || k - j >= m) continue;
      const Eigen::MatrixXd& left = powers[static_cast<std::size_t>(j)];
      const Eigen::MatrixXd& right = powers[static_cast<std::size_t>(k - j)];
      LQ += binomial * left * Q * right.transpose();
      LW += binomial * left.transpose() * W * right;
    }
    form.qd.push_back(LQ / factorial_next);
    form.g.push_back(LW / factorial_next);
    form.noise.push_back(W.cwiseProduct(LQ).sum() / (factorial_next * (k + 2)));
  }
  return form;
}

// out = Σ_k c[k] x^k by Horner's rule, reusing out's storage.
void evaluatePolynomial(const std::vector<Eigen::MatrixXd>& c, double x, Eigen::MatrixXd& out) {
  out = c.back();
  for (std::size_t k = c.size() - 1; k-- > 0;) {
    out *= x;
    out += c[k];
  }
}

void overPolynomial(const PolynomialForm& form, double dt, IntervalTransition& step) {
  evaluatePolynomial(form.phi, dt, step.Phi);
  evaluatePolynomial(form.qd, dt, step.Qd);
  step.Qd *= dt;
  evaluatePolynomial(form.g, dt, step.cost_gramian);
  step.cost_gramian *= dt;
  double noise = form.noise.back();
  for (std::size_t k = form.noise.size() - 1; k-- > 0;) noise = noise * dt + form.noise[k];
  step.noise_cost = noise * dt * dt;
}

// Van Loan (1978), Theorem 1, on the block upper-triangular
//       [ -A'  αW   0  ]                    [ F1  G1  H1 ]
//   C = [  0    A   βQ ] dt,   e^C =        [ 0   F2  G2 ]
//       [  0    0  -A' ]                    [ 0   0   F3 ]
// gives F2 = e^{A dt}, G1 = α ∫ e^{-A'(dt-s)} W e^{As} ds, G2 = β ∫ e^{A(dt-s)} Q e^{-A's} ds and
// H1 = αβ ∫_0^dt ∫_0^s e^{-A'(dt-s)} W e^{A(s-r)} Q e^{-A'r} dr ds, hence
//   G = F2' G1 / α,  Qd = G2 F2' / β,  noise_cost = tr(F2' H1) / (αβ).
// α and β only balance the blocks' norms against A's so that the Padé approximant's
// normwise error does not swamp a small W or Q.
void overVanLoan(const Eigen::MatrixXd& A, const Eigen::MatrixXd& Q, const Eigen::MatrixXd& W,
                 double dt, IntervalTransition& step) {
  const Eigen::Index n = A.rows();
  const double target = std::max(A.lpNorm<1>(), 1.0 / dt);
  const double w_norm = W.lpNorm<1>();
  const double q_norm = Q.lpNorm<1>();
  const double alpha = w_norm > 0.0 ? target / w_norm : 1.0;
  const double beta = q_norm > 0.0 ? target / q_norm : 1.0;

  Eigen::MatrixXd C = Eigen::MatrixXd::Zero(3 * n, 3 * n);
  C.block(0, 0, n, n) = -A.transpose() * dt;
  C.block(0, n, n, n) = (alpha * dt) * W;
  C.block(n, n, n, n) = A * dt;
  C.block(n, 2 * n, n, n) = (beta * dt) * Q;
  C.block(2 * n, 2 * n, n, n) = -A.transpose() * dt;
  const Eigen::MatrixXd E = C.exp();

  step.Phi = E.block(n, n, n, n);
  step.cost_gramian = step.Phi.transpose() * E.block(0, n, n, n) / alpha;
  step.Qd = E.block(n, 2 * n, n, n) * step.Phi.transpose() / beta;
  step.noise_cost = step.Phi.cwiseProduct(E.block(0, 2 * n, n, n)).sum() / (alpha * beta);
}

void symmetrize(Eigen::MatrixXd& m) {
  for (Eigen::Index j = 0; j < m.cols(); ++j) {
    for (Eigen::Index i = 0; i < j; ++i) {
      const double average = 0.5 * (m(i, j) + m(j, i));
      m(i, j) = average;
      m(j, i) = average;
    }
  }
}

void requireSquare(const Eigen::MatrixXd& m, Eigen::Index n, const char* field) {
  if (m.rows() != n || m.cols() != n) {
    throw InputError(kSource, field,
                     std::to_string(n) + " x " + std::to_string(n) + " matrix, got " +
                         std::to_string(m.rows()) + " x " + std::to_string(m.cols()));
  }
  if (!m.allFinite()) throw InputError(kSource, field, "finite entries");
}

}  // namespace

struct LtiTransition::Impl {
  Eigen::MatrixXd A;
  Eigen::MatrixXd Q;  // symmetric part
  Eigen::MatrixXd W;  // symmetric part
  TransitionMethod method = TransitionMethod::kVanLoan;
  double condition = std::numeric_limits<double>::infinity();
  std::optional<ModalForm<double>> real_form;                   // all eigenvalues real
  std::optional<ModalForm<std::complex<double>>> complex_form;  // some complex pair
  std::optional<PolynomialForm> polynomial_form;                // nilpotent A
};

LtiTransition::LtiTransition(const Eigen::MatrixXd& A, const Eigen::MatrixXd& Q,
                             const Eigen::MatrixXd& W, TransitionMethod method) {
  const Eigen::Index n = A.rows();
  if (n < 1) throw InputError(kSource, "A", "a non-empty square matrix");
  requireSquare(A, n, "A");
  requireSquare(Q, n, "Q");
  requireSquare(W, n, "W");

  auto impl = std::make_shared<Impl>();
  impl->A = A;
  impl->Q = 0.5 * (Q + Q.transpose());
  impl->W = 0.5 * (W + W.transpose());

  const bool automatic = method == TransitionMethod::kAutomatic;
  if (automatic || method == TransitionMethod::kPolynomial) {
    impl->polynomial_form = makePolynomialForm(A, impl->Q, impl->W);
    if (impl->polynomial_form) {
      impl->method = TransitionMethod::kPolynomial;
    } else if (!automatic) {
      throw InputError(kSource, "A", "a nilpotent matrix (A^n = 0) for the polynomial method");
    }
  }
  if (automatic || method == TransitionMethod::kModal) {
    const Eigen::EigenSolver<Eigen::MatrixXd> solver(A, /*computeEigenvectors=*/true);
    if (solver.info() == Eigen::Success) {
      const Eigen::VectorXcd& eigenvalues = solver.eigenvalues();
      const Eigen::MatrixXcd V = solver.eigenvectors();
      const auto accept = [&](const auto& form) {
        if (form.diagonalizes) impl->condition = form.condition;
        const double limit = automatic ? kMaxEigenvectorCondition : kDefectiveEigenvectorCondition;
        return !impl->polynomial_form && form.diagonalizes && form.condition < limit;
      };
      if ((eigenvalues.imag().array() == 0.0).all()) {
        auto form = makeModalForm<double>(A, eigenvalues, V, impl->Q, impl->W);
        if (accept(form)) impl->real_form = std::move(form);
      } else {
        auto form = makeModalForm<std::complex<double>>(A, eigenvalues, V, impl->Q, impl->W);
        if (accept(form)) impl->complex_form = std::move(form);
      }
      if (impl->real_form || impl->complex_form) impl->method = TransitionMethod::kModal;
    }
    if (method == TransitionMethod::kModal && impl->method != TransitionMethod::kModal) {
      throw InputError(kSource, "A",
                       "a diagonalizable matrix for the modal method (eigenvector condition "
                       "below 1e8), got condition " +
                           std::to_string(impl->condition));
    }
  }
  impl_ = std::move(impl);
}

IntervalTransition LtiTransition::over(double dt) const {
  IntervalTransition step;
  over(dt, step);
  return step;
}

void LtiTransition::over(double dt, IntervalTransition& step) const {
  if (!(dt >= 0.0) || !std::isfinite(dt)) {
    throw InputError(kSource, "dt", "a finite interval length >= 0, got " + std::to_string(dt));
  }
  const Impl& d = *impl_;
  const Eigen::Index n = d.A.rows();
  if (dt == 0.0) {
    step.Phi.setIdentity(n, n);
    step.Qd.setZero(n, n);
    step.cost_gramian.setZero(n, n);
    step.noise_cost = 0.0;
    return;
  }
  if (d.polynomial_form) {
    overPolynomial(*d.polynomial_form, dt, step);
  } else if (d.real_form) {
    overModal(*d.real_form, dt, step);
  } else if (d.complex_form) {
    overModal(*d.complex_form, dt, step);
  } else {
    overVanLoan(d.A, d.Q, d.W, dt, step);
  }
  // Both are symmetric in exact arithmetic; make them so in floating point too.
  symmetrize(step.Qd);
  symmetrize(step.cost_gramian);
}

int LtiTransition::stateDim() const { return static_cast<int>(impl_->A.rows()); }

TransitionMethod LtiTransition::method() const { return impl_->method; }

double LtiTransition::eigenvectorCondition() const { return impl_->condition; }

TransitionCache::TransitionCache(LtiTransition transition, std::size_t slots)
    : transition_(std::move(transition)) {
  std::size_t size = 1;
  while (size < slots) {
    size *= 2;
    --shift_;
  }
  lengths_.assign(size, std::numeric_limits<double>::quiet_NaN());
  steps_.resize(size);
}

const IntervalTransition& TransitionCache::over(double dt) {
  // Fibonacci hashing: the high bits of the product depend on every bit of dt (lengths that are
  // multiples of one tick differ in their high mantissa bits only).
  const std::size_t slot =
      shift_ >= 64 ? 0
                   : static_cast<std::size_t>((std::bit_cast<std::uint64_t>(dt) *
                                               0x9E3779B97F4A7C15ULL) >>
                                              shift_);
  if (lengths_[slot] == dt) {
    ++hits_;
    return steps_[slot];
  }
  ++misses_;
  transition_.over(dt, computed_);  // a bad dt throws here, before the cache changes
  std::swap(steps_[slot], computed_);
  lengths_[slot] = dt;
  return steps_[slot];
}

}  // namespace sensornet
