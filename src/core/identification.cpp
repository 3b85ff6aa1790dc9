#include "usv_fdi/core/identification.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <unsupported/Eigen/MatrixFunctions>

namespace usvfdi {
namespace {

void require(bool ok, const char* field, double value, const char* what) {
  if (!ok) {
    throw std::invalid_argument(std::string("identification.") + field + " = " +
                                std::to_string(value) + ": " + what);
  }
}

bool finite(const Sample& s) {
  return std::isfinite(s.t) && std::isfinite(s.v) && std::isfinite(s.r) && std::isfinite(s.delta);
}

}  // namespace

void IdentificationParams::validate() const {
  require(std::isfinite(eps1) && eps1 > 0, "eps1", eps1, "must be a positive number");
  if (method == IdentMethod::kPaper) {
    require(std::isfinite(eps2) && eps2 > 0, "eps2", eps2, "must be a positive number");
    require(eps2 != eps1, "eps2", eps2, "must differ from eps1 (R would be singular)");
  }
  require(std::isfinite(gamma) && gamma > 0, "gamma", gamma, "must be a positive number");
  if (normalised) require(std::isfinite(mu) && mu > 0, "mu", mu, "must be a positive number");
  require(std::isfinite(lambda) && lambda > 0, "lambda", lambda, "must be a positive number");
  require(std::isfinite(warmup_time), "warmup_time", warmup_time, "must be a number");
  require(std::isfinite(max_gap) && max_gap > 0, "max_gap", max_gap, "must be positive");
  require(a0.allFinite(), "a0", a0.norm(), "must be finite");
  require(min_excitation >= 0 && min_excitation <= 1, "min_excitation", min_excitation,
          "must lie in [0, 1]");
  require(settle_window > 0, "settle_window", settle_window, "must be positive");
  require(settle_tolerance > 0, "settle_tolerance", settle_tolerance, "must be positive");
  require(settle_windows >= 1, "settle_windows", settle_windows, "must be at least 1");
  require(settle_floor >= 0, "settle_floor", settle_floor, "must not be negative");
  require(max_std_error > 0, "max_std_error", max_std_error, "must be positive");
  require(guard_threshold > 0, "guard_threshold", guard_threshold, "must be positive");
  require(guard_min_shift >= 0, "guard_min_shift", guard_min_shift, "must not be negative");
  require(guard_recent_time > 0, "guard_recent_time", guard_recent_time, "must be positive");
}

const char* to_string(IdentStatus s) {
  switch (s) {
    case IdentStatus::kConverged:
      return "converged";
    case IdentStatus::kWarmingUp:
      return "not converged: filters warming up";
    case IdentStatus::kFrozen:
      return "not converged: frozen (fault suspected)";
    case IdentStatus::kInconsistent:
      return "not converged: equation error inconsistent";
    case IdentStatus::kLowExcitation:
      return "not converged: excitation too low";
    case IdentStatus::kImprecise:
      return "not converged: standard errors too large";
    case IdentStatus::kSettling:
      return "not converged: estimate settling";
  }
  return "?";
}

void Identifier::Memory::step(double E, double dt, const Vec2& q, const Vec2& m, const Vec2& z) {
  const double E2 = E * E;
  Pqq = E * Pqq + dt * (q * q.transpose());
  Yqm = E * Yqm + dt * (q * m.transpose());
  Pzq = E * Pzq + dt * (z * q.transpose());
  Yzm = E * Yzm + dt * (z * m.transpose());
  Zm = E2 * Zm + dt * (z * z.transpose());
  Szz = E * Szz + dt * z.cwiseProduct(z);
  W2 = E2 * W2 + dt;
  decay *= E;
  len += dt;
}

void Identifier::Memory::remove(const Memory& seg, double E) {
  const double E2 = E * E;
  Pqq -= E * seg.Pqq;
  Yqm -= E * seg.Yqm;
  Pzq -= E * seg.Pzq;
  Yzm -= E * seg.Yzm;
  Zm -= E2 * seg.Zm;
  Szz -= E * seg.Szz;
  W2 -= E2 * seg.W2;
}

void Identifier::Memory::append(const Memory& seg) {
  const double E = seg.decay, E2 = E * E;
  Pqq = E * Pqq + seg.Pqq;
  Yqm = E * Yqm + seg.Yqm;
  Pzq = E * Pzq + seg.Pzq;
  Yzm = E * Yzm + seg.Yzm;
  Zm = E2 * Zm + seg.Zm;
  Szz = E * Szz + seg.Szz;
  W2 = E2 * W2 + seg.W2;
}

Identifier::Identifier(const IdentificationParams& params, const Vec2& B, const SpeedParams& speed)
    : p_(params),
      B_(B),
      f1_(params.eps1),
      f2_(params.eps2),
      speed_(speed),
      a_(params.a0),
      a_ref_(params.a0) {
  p_.validate();
  if (!B.allFinite()) throw std::invalid_argument("model.B must be finite");
  const double eps_min = p_.method == IdentMethod::kPaper ? std::min(p_.eps1, p_.eps2) : p_.eps1;
  warmup_ = p_.warmup_time >= 0 ? p_.warmup_time : 10.0 / eps_min;
  est_.A = from_params(a_);
  est_.time_constant = std::numeric_limits<double>::infinity();
  stored_.resize(kStored);
  // Before any estimate: poles -eps1 +- i eps1, so x_aux has two independent components for
  // any B != 0 (B is never an eigenvector of a rotation).
  A_aux_ << -p_.eps1, p_.eps1, -p_.eps1, -p_.eps1;
}

void Identifier::step_instruments(double dt, double delta_prev, double s_prev, double s_now) {
  // At speed ratio s the auxiliary model is x' = s A_aux x + s^2 B delta: A_aux over the
  // vessel's own time s dt, driven by s delta (s in steps of speed.quantum, so that a
  // slowly changing speed does not re-discretise on every sample).
  if (std::abs(s_now - s_aux_) > speed_.params().quantum * s_aux_) {
    s_aux_ = s_now;
    h_aux_ = -1.0;
  }
  const double h = s_aux_ * dt;
  if (std::abs(h - h_aux_) > 1e-9 * h) {
    // Exact ZOH discretisation of x' = A_aux x + B delta over h.
    Eigen::Matrix3d M = Eigen::Matrix3d::Zero();
    M.topLeftCorner<2, 2>() = A_aux_ * h;
    M.topRightCorner<2, 1>() = B_ * h;
    const Eigen::Matrix3d E = M.exp();
    Ad_aux_ = E.topLeftCorner<2, 2>();
    Bd_aux_ = E.topRightCorner<2, 1>();
    h_aux_ = h;
  }
  const Vec2 x_prev = x_aux_;
  x_aux_ = Ad_aux_ * x_aux_ + Bd_aux_ * (speed_.input_factor(s_aux_) / s_aux_ * delta_prev);
  // F1[s x_aux] as the regressor F1[s y] (first-order hold; the instruments need no
  // particular accuracy).
  for (int i = 0; i < 2; ++i) z_(i) = f1_.step(s_prev * x_prev(i), s_now * x_aux_(i), z_(i));
}

void Identifier::refresh_aux_model(double t) {
  if (!std::isnan(t_aux_) && t - t_aux_ < p_.settle_window) return;
  t_aux_ = t;
  // The least-squares estimate of the same memory, when it is defined, with the data still
  // waiting for their verdict: the instruments need no verdict (any A_aux gives valid
  // ones), only to resemble q as early as possible, and a rejected segment leaves this sum
  // with the next refresh.
  Mat2 Pqq = mem_.Pqq, Yqm = mem_.Yqm;
  for (const Pending& f : pending_) {
    Pqq = f.mem.decay * Pqq + f.mem.Pqq;
    Yqm = f.mem.decay * Yqm + f.mem.Yqm;
  }
  Pqq = seg_.decay * Pqq + seg_.Pqq;
  Yqm = seg_.decay * Yqm + seg_.Yqm;
  const double det = Pqq.determinant();
  if (!(det > 1e-6 * Pqq(0, 0) * Pqq(1, 1))) return;
  Mat2 A = (Pqq.partialPivLu().solve(Yqm)).transpose();
  if (!A.allFinite()) return;
  // Slowest pole no slower than -lambda: shift the spectrum left where needed.
  const double half_tr = 0.5 * A.trace(), disc = half_tr * half_tr - A.determinant();
  const double re_max = disc >= 0 ? half_tr + std::sqrt(disc) : half_tr;
  const double shift = std::max(0.0, re_max + p_.lambda);
  A -= shift * Mat2::Identity();
  const double change = (A - A_aux_).norm() / A_aux_.norm();
  if (change <= 1e-3) return;
  A_aux_ = A;
  h_aux_ = -1.0;  // re-discretise on the next step
}

void Identifier::restart_filters(const Sample& s) {
  // Zero initial conditions, as in the paper; the warm-up hides the e^{-eps t} transient.
  q_.setZero();
  m_.setZero();
  qb_.setZero();
  mb_.setZero();
  fd1_ = fd2_ = 0.0;
  qs_.setZero();
  fds_ = 0.0;
  s_prev_ = speed_.ratio();
  z_.setZero();  // x_aux_ carries on: it depends on the rudder only
  // A window must not straddle the restart (the sums after it use fresh filters), and the
  // data no window has judged yet is dropped with them.
  open_[0] = Batch{};
  open_[0].active = true;
  open_[1] = Batch{};  // begins with the second segment, half a window later
  seg_ = Memory{};
  pending_.clear();
  first_segment_ = true;
  prev_ = s;
  have_prev_ = true;
  have_prev2_ = false;
  have_dd_prev_ = false;
  restart_pending_ = false;
  t_start_ = s.t;
  est_.warming_up = true;
}

bool Identifier::update(const Sample& s, bool freeze) {
  if (!finite(s)) return false;
  // Time must increase over every accepted sample, frozen ones included.
  if (!std::isnan(t_last_) && !(s.t > t_last_)) return false;
  t_last_ = s.t;
  est_.t = s.t;
  const double sr = speed_.update(s);
  est_.speed_ratio = sr;
  est_.reference_speed = speed_.reference_speed();
  if (freeze) {
    est_.frozen = true;
    restart_pending_ = true;
    if (!est_.converged) est_.status = IdentStatus::kFrozen;
    return true;
  }
  est_.frozen = false;
  if (restart_pending_ || !have_prev_ || s.t - prev_.t > p_.max_gap) {
    restart_filters(s);
    return true;
  }
  const double dt = s.t - prev_.t;
  const Vec2 y(s.v, s.r), y_prev(prev_.v, prev_.r);
  // Curvature of each input over the step (zero until three samples are known), and its
  // change, the cubic term (zero until four are known).
  Vec3 dd = Vec3::Zero(), c3 = Vec3::Zero();
  double hp = dt;
  if (p_.curvature_correction && have_prev2_) {
    hp = prev_.t - prev2_.t;
    dd(0) = FohLowPass::curvature(prev2_.v, prev_.v, s.v, hp, dt);
    dd(1) = FohLowPass::curvature(prev2_.r, prev_.r, s.r, hp, dt);
    dd(2) = FohLowPass::curvature(prev2_.delta, prev_.delta, s.delta, hp, dt);
    if (p_.cubic_correction && have_dd_prev_) {
      for (int i = 0; i < 3; ++i) {
        c3(i) = FohLowPass::third_difference(dd(i), dd_prev_(i), s.t - t_dd_prev_);
      }
    }
    dd_prev_ = dd;
    t_dd_prev_ = prev2_.t;
    have_dd_prev_ = true;
  }
  f1_.set_step(dt, hp);
  for (int i = 0; i < 2; ++i) q_(i) = f1_.step_cubic(y_prev(i), y(i), dd(i), c3(i), q_(i));
  fd1_ = f1_.step_cubic(prev_.delta, s.delta, dd(2), c3(2), fd1_);
  // The paper's method is kept as written: it knows no speed.
  if (speed_.measured() && p_.method != IdentMethod::kPaper) {
    // The curvature and cubic terms of s y are taken as s times those of y (s changes
    // slowly); the end points are exact.
    const double sp = s_prev_;
    for (int i = 0; i < 2; ++i) {
      qs_(i) = f1_.step_cubic(sp * y_prev(i), sr * y(i), sr * dd(i), sr * c3(i), qs_(i));
    }
    const double kp = speed_.input_factor(sp), kn = speed_.input_factor(sr);
    fds_ = f1_.step_cubic(kp * prev_.delta, kn * s.delta, kn * dd(2), kn * c3(2), fds_);
  } else {
    qs_ = q_;
    fds_ = fd1_;
  }
  m_ = p_.eps1 * (y - q_) - B_ * fds_;
  const bool rudder_iv =
      p_.method == IdentMethod::kKreisselmeier && p_.instruments == Instruments::kRudder;
  if (rudder_iv) {
    step_instruments(dt, prev_.delta, s_prev_, sr);
  } else {
    z_ = qs_;
  }
  if (p_.method == IdentMethod::kPaper) {
    f2_.set_step(dt, hp);
    for (int i = 0; i < 2; ++i) qb_(i) = f2_.step_cubic(y_prev(i), y(i), dd(i), c3(i), qb_(i));
    fd2_ = f2_.step_cubic(prev_.delta, s.delta, dd(2), c3(2), fd2_);
    mb_ = p_.eps2 * (y - qb_) - B_ * fd2_;
  }
  prev2_ = prev_;
  have_prev2_ = true;
  prev_ = s;
  s_prev_ = sr;
  est_.warming_up = s.t - t_start_ < warmup_;
  if (est_.warming_up) {
    if (!est_.converged) est_.status = IdentStatus::kWarmingUp;
    return true;
  }

  if (p_.method == IdentMethod::kPaper) {
    // R = [[q1 q2], [qb1 qb2]]; adj(R) = [[qb2 -q2], [-qb1 q1]].
    Mat2 R;
    R << q_(0), q_(1), qb_(0), qb_(1);
    psi_ = R.determinant();
    Mat2 adj;
    adj << R(1, 1), -R(0, 1), -R(1, 0), R(0, 0);
    const Vec2 h12 = adj * Vec2(m_(0), mb_(0));
    const Vec2 h34 = adj * Vec2(m_(1), mb_(1));
    h_ << h12, h34;
    scale_ = R.col(0).norm() * R.col(1).norm();
    est_.excitation = scale_ > 0 ? std::abs(psi_) / scale_ : 0.0;
  } else {
    step_memories(s.t, dt, rudder_iv);
    if (rudder_iv) refresh_aux_model(s.t);
  }
  advance_scalar_laws(dt);
  update_convergence(s.t);
  return true;
}

void Identifier::step_memories(double t, double dt, bool rudder_iv) {
  const double E = std::exp(-p_.lambda * dt);
  seg_.step(E, dt, qs_, m_, z_);
  // Tapered window sums of z q^T, z m^T, z z^T (two Hann windows, half a window apart).
  const double T_b = kBatchLength / p_.eps1;
  for (Batch& b : open_) {
    if (!b.active) continue;
    b.T += dt;
    const double sn = std::sin(M_PI * std::min(1.0, b.T / T_b));
    const double w = sn * sn;  // Hann window
    b.P += w * dt * (z_ * qs_.transpose());
    b.G += w * dt * (z_ * m_.transpose());
    b.Z += w * w * dt * (z_ * z_.transpose());
    b.H2 += w * w * dt;
  }
  if (seg_.len >= 0.5 * T_b * (1.0 - 1e-9)) close_segment(t, rudder_iv);
}

void Identifier::close_segment(double t, bool rudder_iv) {
  Pending seg;
  seg.mem = seg_;
  seg.id = next_seg_++;
  seg.needed = first_segment_ ? 1 : 2;
  pending_.push_back(seg);
  seg_ = Memory{};
  first_segment_ = false;
  // The window that now spans two segments is complete: its verdict is that of both.
  for (Batch& b : open_) {
    if (!b.active || ++b.segs < 2) continue;
    b.seg1 = pending_.back().id;
    b.seg0 = b.seg1 - 1;  // segment ids are consecutive since the restart it began after
    b.accepted = judge(b);
    b.clock = clock_;
    b.t_end = t;
    windows_.push_back(b);
    if (static_cast<int>(windows_.size()) > kWindows) windows_.pop_front();
    const std::size_t n = pending_.size();
    for (std::size_t k = n >= 2 ? n - 2 : 0; k < n; ++k) {
      ++pending_[k].votes;
      pending_[k].bad = pending_[k].bad || !b.accepted;
    }
    b = Batch{};
    b.active = true;
  }
  for (Batch& b : open_) {
    if (!b.active) {  // the second window begins with the second segment
      b = Batch{};
      b.active = true;
    }
  }
  // Commit the segments every covering window has judged, in order (every closed segment
  // is kept, rejected or not: recent data may replace the memory, see check_memory).
  bool changed = false;
  while (!pending_.empty() && pending_.front().votes >= pending_.front().needed) {
    const Pending& f = pending_.front();
    Stored& st = stored_[f.id % kStored];
    st.mem = f.mem;
    st.id = f.id;
    st.in = !f.bad;
    if (f.bad) {
      inconsistent_run_ += f.mem.len;
      est_.rejected_time += f.mem.len;
      // A window that shares data with a rejected one is no clean sample of the noise.
      for (Batch& w : windows_) {
        if (w.seg0 == f.id || w.seg1 == f.id) w.accepted = false;
      }
    } else {
      mem_.append(f.mem);
      clock_ += f.mem.len;
      st.clock = clock_;
      inconsistent_run_ = 0.0;
      changed = true;
    }
    pending_.pop_front();
  }
  // With more data the memory may show that something it took in earlier disagrees with
  // the rest (a fault before the guard could judge): take it out again. Or the recent data,
  // consistent among themselves, show that the memory as a whole is wrong.
  if (changed) rejudge();
  if (check_memory(t)) changed = true;
  est_.inconsistent_time = inconsistent_run_;
  if (est_.converged && supervised_ && inconsistent_run_ >= p_.guard_recent_time) {
    // After convergence a lasting change of the data that the isolation thread does not
    // take for a sensor fault is a change of the vessel: forgetting follows it.
    guard_suspended_ = true;
    inconsistent_run_ = 0.0;
  }
  if (changed) {
    commit_mixing(rudder_iv);
    update_std_error();
  }
}

bool Identifier::check_memory(double t) {
  // Before convergence: the memory's estimate A_L against the estimate A_s of the windows of
  // the last guard_recent_time alone (accepted or not). When the recent data agree among
  // themselves (no window beyond the threshold under A_s, with the noise level of their
  // own fit) and A_s differs from A_L by more than both estimates' uncertainties allow (a
  // Wald test, chi-square with 4 degrees of freedom when both describe the same vessel),
  // the memory is what is wrong: a fault in it from the start, or from before the guard
  // could judge, that the healthy data since cannot outweigh (the memory may even reject
  // them). It is rebuilt from the recent segments. Recent data that disagree among
  // themselves (a fault still in the recent span) change nothing.
  if (!p_.guard || est_.converged || windows_.empty()) return false;
  Mat2 AtL;
  if (!memory_estimate(&AtL)) return false;
  const auto final_segment = [this](std::uint64_t id) {
    return stored_[id % kStored].id == id;  // stored once every covering window judged it
  };
  const double T_b = kBatchLength / p_.eps1;
  std::vector<const Batch*> S;
  for (const Batch& b : windows_) {
    if (b.t_end < t - p_.guard_recent_time + 0.5 * T_b) continue;
    if (!final_segment(b.seg0) || !final_segment(b.seg1)) continue;
    if (!S.empty() && b.seg0 > S.back()->seg1) return false;  // a gap (restart) in the span
    S.push_back(&b);
  }
  const int needed = static_cast<int>(2.0 * p_.guard_recent_time / T_b) - 2;
  if (static_cast<int>(S.size()) < std::max(needed, kMinJudge)) return false;
  Mat2 P = Mat2::Zero(), G = Mat2::Zero(), Z = Mat2::Zero();
  for (const Batch* b : S) {
    P += b->P;
    G += b->G;
    Z += b->Z;
  }
  if (!(std::abs(P.determinant()) > 0)) return false;
  const Mat2 Ps = P.inverse();
  const Mat2 AtS = Ps * G;
  if (!AtS.allFinite()) return false;
  // The recent data's own noise level (robust: the median window) and their worst window.
  std::vector<double> q[2];
  std::vector<Mat2> Zi(S.size());
  for (std::size_t k = 0; k < S.size(); ++k) {
    if (!(S[k]->Z.determinant() > 0)) return false;
    Zi[k] = S[k]->Z.inverse();
    const Mat2 r = S[k]->G - S[k]->P * AtS;
    for (int i = 0; i < 2; ++i) q[i].push_back(r.col(i).dot(Zi[k] * r.col(i)));
  }
  Vec2 s2;
  for (int i = 0; i < 2; ++i) {
    std::vector<double> v = q[i];
    auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
    std::nth_element(v.begin(), mid, v.end());
    s2(i) = *mid / (2.0 * M_LN2);
  }
  if (!(s2.minCoeff() > 0)) return false;
  for (std::size_t k = 0; k < S.size(); ++k) {
    if (!(q[0][k] / s2(0) + q[1][k] / s2(1) <= p_.guard_threshold)) return false;
  }
  // Wald test of A_s = A_L: Cov(row i) = s_i (Ps Z Ps^T + Pzq^-1 Zm Pzq^-T).
  const Mat2 PL = mem_.Pzq.inverse();
  const Mat2 C = Ps * Z * Ps.transpose() + PL * mem_.Zm * PL.transpose();
  if (!(C.determinant() > 0)) return false;
  const Mat2 Ci = C.inverse();
  const Mat2 d = AtS - AtL;
  double W = 0.0;
  for (int i = 0; i < 2; ++i) W += d.col(i).dot(Ci * d.col(i)) / s2(i);
  est_.memory_mismatch = W;
  if (!(W > p_.guard_threshold)) return false;
  // Rebuild the memory from the recent segments, oldest first.
  mem_ = Memory{};
  for (Stored& st : stored_) st.in = false;
  for (std::uint64_t id = S.front()->seg0; id <= S.back()->seg1; ++id) {
    Stored& st = stored_[id % kStored];
    if (st.id != id) continue;
    mem_.append(st.mem);
    clock_ += st.mem.len;
    st.clock = clock_;
    st.in = true;
  }
  const std::uint64_t first = S.front()->seg0;
  for (Batch& b : windows_) {
    b.accepted = b.seg0 >= first && final_segment(b.seg0) && final_segment(b.seg1);
    b.clock = clock_;
  }
  inconsistent_run_ = 0.0;
  settled_count_ = 0;
  t_ref_ = kNaN;
  est_.std_error = Vec4::Constant(kNaN);
  ++est_.resets;
  return true;
}

int Identifier::accepted_windows() const {
  int n = 0;
  for (const Batch& b : windows_) n += b.accepted;
  return n;
}

bool Identifier::memory_estimate(Mat2* At) const {
  const Mat2& P = mem_.Pzq;
  const double det = P.determinant();
  if (!std::isfinite(det) || !(std::abs(det) > 0)) return false;
  *At = P.inverse() * mem_.Yzm;
  return At->allFinite();
}

void Identifier::update_noise(const Mat2& At) {
  // The long-run variance density s_i of the equation error e_i = m_i - a_i q, from the
  // accepted windows: r = G_i - P a_i has covariance s_i int h^2 z z^T, so r^T Z^-1 r / s_i
  // is chi-square with 2 degrees of freedom. The median (2 ln 2 of them) is robust to the
  // few windows a fault may have brought in; normalising by each window's own Z makes it
  // independent of the instruments' scale (a refreshed auxiliary model changes nothing).
  noise_.setZero();
  std::vector<double> q[2];
  for (const Batch& b : windows_) {
    if (!b.accepted || !(b.Z.determinant() > 0)) continue;
    const Mat2 Zi = b.Z.inverse();
    const Mat2 r = b.G - b.P * At;
    for (int i = 0; i < 2; ++i) q[i].push_back(r.col(i).dot(Zi * r.col(i)));
  }
  if (static_cast<int>(q[0].size()) < kMinBatches) return;
  for (int i = 0; i < 2; ++i) {
    auto mid = q[i].begin() + static_cast<std::ptrdiff_t>(q[i].size() / 2);
    std::nth_element(q[i].begin(), mid, q[i].end());
    noise_(i) = *mid / (2.0 * M_LN2);
  }
}

bool Identifier::judge(const Batch& b) {
  // The window's equation-error sums r_i = int h z e_i = G_i - P a^_i (a^_i: row i of the
  // memory's estimate) against what healthy data give: Var(r_i) = s_i (int h^2 z z^T + P
  // Pzq^-1 Zm Pzq^-T P^T), the window's noise plus the memory's uncertainty in a^_i, so
  // T = sum_i r_i^T Var(r_i)^-1 r_i is chi-square with 4 degrees of freedom on healthy
  // data. A sensor fault (bias, drift, scale, a noise burst, spikes) breaks m = A q by far
  // more: the window, and the data it covers, stay out of the memory.
  est_.consistent = true;
  est_.consistency = 0.0;
  Mat2 At;
  if (!p_.guard || accepted_windows() < kMinJudge || !memory_estimate(&At)) return true;
  update_noise(At);
  if (!(noise_.minCoeff() > 0)) return true;
  const Mat2 Pinv = mem_.Pzq.inverse();
  const Mat2 S = b.Z + b.P * (Pinv * mem_.Zm * Pinv.transpose()) * b.P.transpose();
  if (!(S.determinant() > 0)) return true;
  const Mat2 Si = S.inverse();
  const Mat2 r = b.G - b.P * At;
  double T = 0.0;
  for (int i = 0; i < 2; ++i) T += r.col(i).dot(Si * r.col(i)) / noise_(i);
  // Materiality: how far the window would move A^ (rounding-level inconsistencies of exact
  // data move nothing).
  const Mat2 D = (mem_.Pzq + b.P).inverse() * r;
  double shift = 0.0;
  for (int i = 0; i < 2; ++i) {
    for (int j = 0; j < 2; ++j) {
      shift = std::max(shift, std::abs(D(j, i)) / std::max(std::abs(At(j, i)), p_.settle_floor));
    }
  }
  const bool ok = !(T > p_.guard_threshold && shift > p_.guard_min_shift);
  est_.consistent = ok;
  est_.consistency = T;
  if (!ok) {
    ++est_.rejected_windows;
    settled_count_ = 0;
  }
  if (guard_suspended_) {
    if (ok) guard_suspended_ = false;  // the data agree with the memory again
    return true;
  }
  return ok;
}

bool Identifier::rejudge() {
  // Every accepted window whose data are still in the memory, against the memory itself
  // (in-sample, so Var(r_i) <= s_i Z: the test is conservative). The worst one beyond the
  // threshold leaves, and the memory is judged again without it, as long as one does: a
  // fault that came in before the guard could judge (the first kMinJudge windows, or right
  // after a reset) leaves once the healthy data outweigh it.
  if (!p_.guard || guard_suspended_) return false;
  const auto in_memory = [this](std::uint64_t id) {
    const Stored& st = stored_[id % kStored];
    return st.id == id && st.in;
  };
  bool removed = false;
  for (int iter = 0; iter < 8; ++iter) {
    Mat2 At;
    if (accepted_windows() < kMinJudge || !memory_estimate(&At)) break;
    update_noise(At);
    if (!(noise_.minCoeff() > 0)) break;
    double worst = 0.0;
    int j_worst = -1;
    Mat2 r_worst = Mat2::Zero();
    for (int j = 0; j < static_cast<int>(windows_.size()); ++j) {
      const Batch& b = windows_[j];
      if (!b.accepted || !in_memory(b.seg0) || !in_memory(b.seg1) || !(b.Z.determinant() > 0))
        continue;
      const Mat2 Zi = b.Z.inverse();
      const Mat2 r = b.G - b.P * At;
      double T = 0.0;
      for (int i = 0; i < 2; ++i) T += r.col(i).dot(Zi * r.col(i)) / noise_(i);
      if (T > worst) {
        worst = T;
        j_worst = j;
        r_worst = r;
      }
    }
    if (j_worst < 0 || !(worst > p_.guard_threshold)) break;
    const Batch& b = windows_[j_worst];
    const Mat2 D = (mem_.Pzq - b.P).inverse() * r_worst;  // the shift of A^ without it
    double shift = 0.0;
    for (int i = 0; i < 2; ++i) {
      for (int k = 0; k < 2; ++k) {
        shift = std::max(shift, std::abs(D(k, i)) / std::max(std::abs(At(k, i)), p_.settle_floor));
      }
    }
    if (!(shift > p_.guard_min_shift)) break;
    const std::uint64_t s0 = b.seg0, s1 = b.seg1;
    remove_segment(s0);
    remove_segment(s1);
    for (Batch& w : windows_) {
      if (w.seg0 == s0 || w.seg1 == s0 || w.seg0 == s1 || w.seg1 == s1) w.accepted = false;
    }
    ++est_.removed_windows;
    settled_count_ = 0;
    removed = true;
  }
  return removed;
}

void Identifier::remove_segment(std::uint64_t id) {
  Stored& st = stored_[id % kStored];
  if (st.id != id || !st.in) return;
  mem_.remove(st.mem, std::exp(-p_.lambda * (clock_ - st.clock)));
  st.in = false;
}

void Identifier::commit_mixing(bool rudder_iv) {
  Mat2 P = mem_.Pqq, Yv = mem_.Yqm;
  if (rudder_iv) {
    // Rescale the instruments' rows to the RMS of q's components (the identity only needs
    // an invertible row scaling).
    Vec2 sc;
    for (int i = 0; i < 2; ++i) {
      sc(i) = mem_.Szz(i) > 0 ? std::sqrt(std::max(0.0, mem_.Pqq(i, i)) / mem_.Szz(i)) : 0.0;
    }
    P = sc.asDiagonal() * mem_.Pzq;
    Yv = sc.asDiagonal() * mem_.Yzm;
  }
  psi_ = P.determinant();
  Mat2 adj;
  adj << P(1, 1), -P(0, 1), -P(1, 0), P(0, 0);
  const Mat2 Z = adj * Yv;  // = psi A^T
  h_ << Z(0, 0), Z(1, 0), Z(0, 1), Z(1, 1);
  // |det(int z q^T)| <= sqrt(Szz0 Szz1 Pqq00 Pqq11) (Hadamard, Cauchy-Schwarz), so this
  // lies in [0, 1]; for z = q it is psi / (Phi00 Phi11) = 1 - (correlation of q1, q2)^2.
  scale_ = mem_.Pqq(0, 0) * mem_.Pqq(1, 1);
  est_.excitation = scale_ > 0 ? std::clamp(std::abs(psi_) / scale_, 0.0, 1.0) : 0.0;
}

void Identifier::update_std_error() {
  // Row i of A^ is off by Pzq^-1 sum w z e_i: Cov_i = Pzq^-1 V_i Pzq^-T, with V_i = (the
  // recent rate of Var(b_i)) x (the memory's sum of squared weights), from the last
  // kStdBatches accepted windows (tapered batch sums b = G - P A^T, see Estimate::std_error).
  Mat2 At;
  if (!memory_estimate(&At)) return;
  std::array<Mat2, 2> R{Mat2::Zero(), Mat2::Zero()};
  double T = 0.0;
  int n = 0;
  for (auto it = windows_.rbegin(); it != windows_.rend() && n < kStdBatches; ++it) {
    if (!it->accepted) continue;
    const Mat2 b = it->G - it->P * At;  // column i: tapered sum of z e_i over the batch
    for (int i = 0; i < 2; ++i) R[i] += b.col(i) * b.col(i).transpose();
    T += it->H2;  // Var(b_j) = (long-run variance rate) x int h^4 dt
    ++n;
  }
  if (n < kMinBatches) return;
  const Mat2 Pinv = mem_.Pzq.inverse();
  // The b_j sum to ~0 over the memory (A^ solves its normal equations), so n batches carry
  // n - 2 degrees of freedom per row: scale by n / (n - 2).
  const double dof = n / std::max(1.0, n - 2.0);
  std_error_dof_ = n - 2.0;
  for (int i = 0; i < 2; ++i) {
    const Mat2 C = Pinv * (R[i] * (dof * mem_.W2 / T)) * Pinv.transpose();
    for (int j = 0; j < 2; ++j) est_.std_error(2 * i + j) = std::sqrt(std::max(0.0, C(j, j)));
    row_cov_[i] = C;
  }
}

void Identifier::advance_scalar_laws(double dt) {
  const double psi2 = psi_ * psi_;
  const double rate =
      p_.normalised ? p_.gamma * psi2 / (p_.mu * scale_ * scale_ + psi2) : p_.gamma * psi2;
  est_.psi = psi_;
  est_.time_constant = rate > 0 ? 1.0 / rate : std::numeric_limits<double>::infinity();
  if (!(psi2 > 0) || !std::isfinite(rate)) return;
  // Exact solution of a' = -rate (a - h/psi) over dt with psi, h held.
  const double w = -std::expm1(-rate * dt);
  for (int n = 0; n < 4; ++n) {
    const double target = h_(n) / psi_;
    a_(n) += w * (target - a_(n));
  }
  est_.A = from_params(a_);
  ++est_.updates;
}

double Identifier::relative_std_error(const Vec4& a) const {
  // The standard errors come from few batches at first, so their own uncertainty counts:
  // the upper 90 % confidence bound, se sqrt(k / chi2_k(0.1)), k the noise level's degrees
  // of freedom (Wilson-Hilferty for the quantile). NaN (too few batches) gives infinity.
  const double k = std::max(1.0, std_error_dof_);
  const double c = 2.0 / (9.0 * k);
  const double q = k * std::pow(std::max(1e-3, 1.0 - c - 1.2816 * std::sqrt(c)), 3.0);
  const double upper2 = k / q;
  double worst = 0.0;
  if (p_.precision == Precision::kCoefficients) {
    for (int n = 0; n < 4; ++n) {
      const double r =
          std::sqrt(upper2) * est_.std_error(n) / std::max(std::abs(a(n)), p_.settle_floor);
      worst = std::isnan(r) ? std::numeric_limits<double>::infinity() : std::max(worst, r);
    }
    return worst;
  }
  for (int i = 0; i < 2; ++i) {
    // E[(da_i^T q)^2] = tr(Cov_i Q) over the memory (Q: its sum of q q^T).
    const double err = std::sqrt(upper2 * (row_cov_[i] * mem_.Pqq).trace());
    const double r = err / prediction_scale(a, i);
    worst = std::isnan(r) ? std::numeric_limits<double>::infinity() : std::max(worst, r);
  }
  return worst;
}

double Identifier::prediction_scale(const Vec4& a, int i) const {
  // The RMS of each term a_ij q_j, added: the terms of a_i^T q may cancel (in a steady turn
  // A x = -B delta), and a relative error must not grow with that cancellation.
  const Mat2& Q = mem_.Pqq;
  const double floor = p_.settle_floor * std::sqrt(Q.trace());
  const double s = std::abs(a(2 * i)) * std::sqrt(std::max(0.0, Q(0, 0))) +
                   std::abs(a(2 * i + 1)) * std::sqrt(std::max(0.0, Q(1, 1)));
  return std::max(s, floor);
}

double Identifier::relative_prediction_change(const Vec4& d, const Vec4& a) const {
  double worst = 0.0;
  if (p_.precision == Precision::kCoefficients) {
    for (int n = 0; n < 4; ++n) {
      worst = std::max(worst, std::abs(d(n)) / (std::abs(a(n)) + p_.settle_floor));
    }
    return worst;
  }
  for (int i = 0; i < 2; ++i) {
    const Vec2 di(d(2 * i), d(2 * i + 1));
    const double r = std::sqrt(std::max(0.0, di.dot(mem_.Pqq * di))) / prediction_scale(a, i);
    worst = std::isnan(r) ? std::numeric_limits<double>::infinity() : std::max(worst, r);
  }
  return worst;
}

void Identifier::update_convergence(double t) {
  if (std::isnan(t_ref_)) {
    t_ref_ = t;
    a_ref_ = a_;
    return;
  }
  if (t - t_ref_ < p_.settle_window) return;
  // How much the last window's change of A moved the model's prediction (relative).
  const double d = relative_prediction_change(a_ - a_ref_, a_);
  est_.settling = d;
  bool precise = true;
  if (p_.method == IdentMethod::kKreisselmeier) {
    // The standard errors come from few batches at first, so their own uncertainty counts:
    // the test uses their upper 90 % confidence bound, se sqrt(k / chi2_k(0.1)), k = batches
    // - 2 degrees of freedom (Wilson-Hilferty for the quantile). NaN (too few batches) fails.
    est_.uncertainty = relative_std_error(a_);
    precise = est_.uncertainty <=
              (p_.precision == Precision::kPrediction ? p_.max_prediction_error : p_.max_std_error);
  }
  // Nothing converges on data the guard keeps out, nor while it keeps data out, nor before
  // it can judge (with the guard on).
  const bool guarded = p_.guard && p_.method == IdentMethod::kKreisselmeier;
  const bool consistent =
      est_.consistent && inconsistent_run_ == 0.0 && (!guarded || accepted_windows() >= kMinJudge);
  const bool excited = est_.excitation >= p_.min_excitation &&
                       est_.time_constant <= p_.settle_window * p_.settle_windows;
  settled_count_ =
      (d < p_.settle_tolerance && precise && excited && consistent) ? settled_count_ + 1 : 0;
  if (settled_count_ >= p_.settle_windows) est_.converged = true;
  if (est_.converged) {
    est_.status = IdentStatus::kConverged;
  } else {
    est_.status = !consistent ? IdentStatus::kInconsistent
                  : !excited  ? IdentStatus::kLowExcitation
                  : !precise  ? IdentStatus::kImprecise
                              : IdentStatus::kSettling;
  }
  t_ref_ = t;
  a_ref_ = a_;
}

}  // namespace usvfdi
