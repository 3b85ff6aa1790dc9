// Identification of the unknown sway-yaw matrix A by DREM (dynamic regressor extension
// and mixing), Bazylev & Margun section 3, with the better-conditioned variant of
// DESIGN.md section 2 (normalised update, Kreisselmeier regressor extension).
//
//   q = F1[y],  m = p F1[y] - B F1[delta] = eps1 (y - q) - B F1[delta]   =>  m = A q
//   paper:        R = [[q1 q2], [qb1 qb2]] (second filter eps2), G1 = [m1 mb1]^T, G2 = [m2 mb2]^T,
//                 psi = det R, [h1 h2]^T = adj(R) G1, [h3 h4]^T = adj(R) G2  =>  h_n = psi a_n
//   kreisselmeier: Phi' = -lambda Phi + q q^T, Y' = -lambda Y + q m^T  =>  Y = Phi A^T,
//                 psi = det Phi, adj(Phi) Y = psi A^T
//   scalar laws:  a_n' = gamma psi (h_n - psi a_n)                 (paper)
//                 a_n' = gamma psi (h_n - psi a_n) / (mu + psi^2)   (normalised)
// Each scalar law is advanced by its exact solution over one step, which is stable for any
// gain and step: a <- h/psi + (a - h/psi) exp(-gamma psi^2 dt / (mu + psi^2)).
#pragma once

#include <cstdint>

#include "usv_fdi/core/filters.hpp"
#include "usv_fdi/core/types.hpp"

namespace usvfdi {

enum class IdentMethod : std::uint8_t {
  kPaper = 0,      ///< two filters eps1, eps2, as written in the paper
  kKreisselmeier,  ///< one filter eps1 + Kreisselmeier extension (default, best on benchmark)
};

struct IdentificationParams {
  IdentMethod method = IdentMethod::kKreisselmeier;
  double eps1 = 1.0;        ///< filter F1 bandwidth [1/s]
  double eps2 = 2.0;        ///< filter F2 bandwidth [1/s] (paper method only)
  double gamma = 1.0;       ///< adaptation gain (units depend on mu; see header comment)
  bool normalised = true;   ///< false: the paper's law a' = gamma psi (h - psi a)
  double mu = 1e-14;        ///< normaliser of the normalised law (> 0)
  double lambda = 0.01;     ///< Kreisselmeier forgetting rate [1/s] (100 s memory)
  double warmup_time = -1;  ///< filter warm-up before regressions are used [s]; <0: 10/min(eps)
  double max_gap = 1.0;     ///< a time gap longer than this restarts the filters [s]
  bool curvature_correction = true;  ///< filter the inputs' curvature too (O(h^3) error)
  Vec4 a0 = Vec4::Zero();            ///< initial estimate [a1 a2 a3 a4]
  // Convergence criterion (reported, and what arms the isolation thread).
  double min_excitation = 0.01;    ///< normalised excitation in [0,1] needed to converge
  double settle_window = 1.0;      ///< length of one settling window [s]
  double settle_tolerance = 0.01;  ///< max relative change of every a_n over one window
  int settle_windows = 3;          ///< consecutive settled windows needed
  double settle_floor = 1e-4;      ///< absolute floor of the relative change's denominator

  /// Throws std::invalid_argument naming the offending field.
  void validate() const;
};

/// One snapshot of the identification state (published by the identification thread).
struct Estimate {
  double t = kNaN;            ///< time of the last sample used [s]
  Mat2 A = Mat2::Zero();      ///< current estimate of A
  bool converged = false;     ///< sticky once the criterion held
  double excitation = 0.0;    ///< normalised excitation of the extended regressor, [0,1]
  double psi = 0.0;           ///< mixed regressor psi
  double time_constant = 0;   ///< current time constant of the scalar laws [s] (inf: none)
  double settling = 1.0;      ///< max relative change of a_n over the last window
  bool frozen = false;        ///< last sample was not used because of a freeze request
  bool warming_up = true;     ///< filters are settling; regressions not used yet
  std::uint64_t updates = 0;  ///< samples that updated the estimate
};

class Identifier {
 public:
  /// Throws std::invalid_argument on bad parameters.
  Identifier(const IdentificationParams& params, const Vec2& B);

  /// Feeds one sample. With freeze = true nothing in the estimator's memory changes (the
  /// filters restart, with a warm-up, on the first sample after the freeze).
  /// Returns false (and changes nothing) when the sample is unusable: a value is not
  /// finite, or t does not increase.
  bool update(const Sample& s, bool freeze);

  const Estimate& estimate() const { return est_; }
  const IdentificationParams& params() const { return p_; }

  /// Latest mixed quantities, for tests of the DREM identity h_n = psi a_n.
  double psi() const { return psi_; }
  const Vec4& h() const { return h_; }
  /// Latest regression pair (m = A q holds for noise-free data).
  const Vec2& q() const { return q_; }
  const Vec2& m() const { return m_; }

 private:
  void restart_filters(const Sample& s);
  void advance_scalar_laws(double dt);
  void update_convergence(double t);

  IdentificationParams p_;
  Vec2 B_;
  double warmup_;
  FohLowPass f1_, f2_;
  bool have_prev_ = false;
  bool restart_pending_ = true;
  Sample prev_{};
  Sample prev2_{};  ///< the sample before prev_ (for the curvature)
  bool have_prev2_ = false;
  double t_start_ = kNaN;  ///< time the filters (re)started
  // filter states: F1[y], F1[delta], F2[y], F2[delta]
  Vec2 q_ = Vec2::Zero(), m_ = Vec2::Zero();
  Vec2 qb_ = Vec2::Zero(), mb_ = Vec2::Zero();
  double fd1_ = 0.0, fd2_ = 0.0;
  // Kreisselmeier memory
  Mat2 Phi_ = Mat2::Zero(), Y_ = Mat2::Zero();
  bool ext_started_ = false;
  double psi_ = 0.0;
  Vec4 h_ = Vec4::Zero();
  Vec4 a_;
  // convergence bookkeeping
  Vec4 a_ref_;
  double t_ref_ = kNaN;
  int settled_count_ = 0;
  Estimate est_;
};

}  // namespace usvfdi
