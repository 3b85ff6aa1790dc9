#include "usv_fdi/core/consistency_guard.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "usv_fdi/core/robust.hpp"

namespace usvfdi {
namespace {

/// M^-1 R by an LU solve; false when M is singular or the result is not finite.
bool solve(const Mat2& M, const Mat2& R, Mat2* X) {
  const double det = M.determinant();
  if (!std::isfinite(det) || !(std::abs(det) > 0)) return false;
  *X = M.partialPivLu().solve(R);
  return X->allFinite();
}

/// M^-1 S M^-T for a symmetric S, by two solves.
bool sandwich(const Mat2& M, const Mat2& S, Mat2* X) {
  Mat2 G;
  if (!solve(M, S, &G) || !solve(M, G.transpose(), X)) return false;
  return true;
}

/// x^T S^-1 x for a symmetric positive definite 2x2 S of determinant det: x^T adj(S) x / det
/// (closed form: the guard evaluates it for every window it keeps, several hundred times each
/// time a segment closes, where a factorisation tripled the identification's cost).
double inverse_quadratic(const Mat2& S, double det, const Vec2& x) {
  return (S(1, 1) * x(0) * x(0) - (S(0, 1) + S(1, 0)) * x(0) * x(1) + S(0, 0) * x(1) * x(1)) / det;
}

/// sum_i r_i^T S^-1 r_i / s_i over the columns r_i of r, S positive definite.
double weighted_chi2(const Mat2& S, const Mat2& r, const Vec2& s) {
  const double det = S.determinant();
  double T = 0.0;
  for (int i = 0; i < 2; ++i) T += inverse_quadratic(S, det, r.col(i)) / s(i);
  return T;
}

}  // namespace

void KreisselmeierMemory::step(double E, double dt, const Vec2& q, const Vec2& m, const Vec2& z) {
  const double E2 = E * E;
  Phi_ls = E * Phi_ls + dt * (q * q.transpose());
  Y_ls = E * Y_ls + dt * (q * m.transpose());
  Phi = E * Phi + dt * (z * q.transpose());
  Y = E * Y + dt * (z * m.transpose());
  Zw2 = E2 * Zw2 + dt * (z * z.transpose());
  Szz = E * Szz + dt * z.cwiseProduct(z);
  W2 = E2 * W2 + dt;
  decay *= E;
  len += dt;
}

void KreisselmeierMemory::remove(const KreisselmeierMemory& seg, double E) {
  const double E2 = E * E;
  Phi_ls -= E * seg.Phi_ls;
  Y_ls -= E * seg.Y_ls;
  Phi -= E * seg.Phi;
  Y -= E * seg.Y;
  Zw2 -= E2 * seg.Zw2;
  Szz -= E * seg.Szz;
  W2 -= E2 * seg.W2;
}

void KreisselmeierMemory::append(const KreisselmeierMemory& seg) {
  const double E = seg.decay, E2 = E * E;
  Phi_ls = E * Phi_ls + seg.Phi_ls;
  Y_ls = E * Y_ls + seg.Y_ls;
  Phi = E * Phi + seg.Phi;
  Y = E * Y + seg.Y;
  Zw2 = E2 * Zw2 + seg.Zw2;
  Szz = E * Szz + seg.Szz;
  W2 = E2 * W2 + seg.W2;
}

bool KreisselmeierMemory::estimate(Mat2* At) const { return solve(Phi, Y, At); }

bool GuardWindow::chi2(const Mat2& At, Vec2* q) const {
  const double det = Z.determinant();
  if (!(det > 0)) return false;
  const Mat2 r = Y - Phi * At;
  for (int i = 0; i < 2; ++i) (*q)(i) = inverse_quadratic(Z, det, r.col(i));
  return true;
}

ConsistencyGuard::ConsistencyGuard(const Settings& s) : s_(s), stored_(kStored) { restart(); }

void ConsistencyGuard::restart() {
  open_[0] = GuardWindow{};
  open_[0].active = true;
  open_[1] = GuardWindow{};  // begins with the second segment, half a window later
  seg_ = KreisselmeierMemory{};
  pending_.clear();
  first_segment_ = true;
}

ConsistencyGuard::Change ConsistencyGuard::add(double t, double dt, const Vec2& q, const Vec2& m,
                                               const Vec2& z, bool converged, bool supervised) {
  Change c;
  seg_.step(std::exp(-s_.lambda * dt), dt, q, m, z);
  // Tapered window sums of z q^T, z m^T, z z^T (two Hann windows, half a window apart).
  const double T_b = kBatchLength / s_.eps1;
  for (GuardWindow& w : open_) {
    if (!w.active) continue;
    w.T += dt;
    const double sn = std::sin(M_PI * std::min(1.0, w.T / T_b));
    const double h = sn * sn;  // Hann window
    w.Phi += h * dt * (z * q.transpose());
    w.Y += h * dt * (z * m.transpose());
    w.Z += h * h * dt * (z * z.transpose());
    w.H2 += h * h * dt;
  }
  if (seg_.len >= 0.5 * T_b * (1.0 - 1e-9)) c.memory = close_segment(t, converged, supervised, &c);
  return c;
}

void ConsistencyGuard::least_squares_with_pending(Mat2* Phi_ls, Mat2* Y_ls) const {
  *Phi_ls = mem_.Phi_ls;
  *Y_ls = mem_.Y_ls;
  for (const Pending& f : pending_) {
    *Phi_ls = f.mem.decay * *Phi_ls + f.mem.Phi_ls;
    *Y_ls = f.mem.decay * *Y_ls + f.mem.Y_ls;
  }
  *Phi_ls = seg_.decay * *Phi_ls + seg_.Phi_ls;
  *Y_ls = seg_.decay * *Y_ls + seg_.Y_ls;
}

int ConsistencyGuard::accepted_windows() const {
  if (accepted_gen_ != gen_) {
    accepted_n_ = 0;
    for (const GuardWindow& w : windows_) accepted_n_ += w.accepted;
    accepted_gen_ = gen_;
  }
  return accepted_n_;
}

bool ConsistencyGuard::consistent() const {
  return report_.consistent && inconsistent_run_ == 0.0 &&
         (!s_.enabled || accepted_windows() >= kMinJudge);
}

bool ConsistencyGuard::in_memory(std::uint64_t id) const {
  const Stored& st = stored_[id % kStored];
  return st.id == id && st.in;
}

bool ConsistencyGuard::final_segment(std::uint64_t id) const {
  return stored_[id % kStored].id == id;  // stored once every covering window judged it
}

double ConsistencyGuard::relative_shift(const Mat2& M, const Mat2& r, const Mat2& At) const {
  Mat2 D;
  if (!solve(M, r, &D)) return std::numeric_limits<double>::infinity();
  double shift = 0.0;
  for (int i = 0; i < 2; ++i) {
    for (int j = 0; j < 2; ++j) {
      shift = std::max(shift, std::abs(D(j, i)) / std::max(std::abs(At(j, i)), s_.settle_floor));
    }
  }
  return shift;
}

bool ConsistencyGuard::close_segment(double t, bool converged, bool supervised, Change* c) {
  Pending seg;
  seg.mem = seg_;
  seg.id = next_seg_++;
  seg.needed = first_segment_ ? 1 : 2;
  pending_.push_back(seg);
  seg_ = KreisselmeierMemory{};
  first_segment_ = false;
  // The window that now spans two segments is complete: its verdict is that of both.
  for (GuardWindow& w : open_) {
    if (!w.active || ++w.segs < 2) continue;
    w.seg1 = pending_.back().id;
    w.seg0 = w.seg1 - 1;  // segment ids are consecutive since the restart it began after
    w.accepted = judge(w, c);
    w.clock = clock_;
    w.t_end = t;
    windows_.push_back(w);
    if (static_cast<int>(windows_.size()) > kWindows) windows_.pop_front();
    ++gen_;
    const std::size_t n = pending_.size();
    for (std::size_t k = n >= 2 ? n - 2 : 0; k < n; ++k) {
      ++pending_[k].votes;
      pending_[k].bad = pending_[k].bad || !w.accepted;
    }
    w = GuardWindow{};
    w.active = true;
  }
  for (GuardWindow& w : open_) {
    if (!w.active) {  // the second window begins with the second segment
      w = GuardWindow{};
      w.active = true;
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
      report_.rejected_time += f.mem.len;
      // A window that shares data with a rejected one is no clean sample of the noise.
      for (GuardWindow& w : windows_) {
        if (w.seg0 == f.id || w.seg1 == f.id) w.accepted = false;
      }
      ++gen_;
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
  if (changed) rejudge(c);
  if (!converged && check_memory(t)) {
    c->unsettled = c->reset = true;
    changed = true;
  }
  report_.inconsistent_time = inconsistent_run_;
  if (converged && supervised && inconsistent_run_ >= s_.recent_time) {
    // After convergence a lasting change of the data that the isolation thread does not
    // take for a sensor fault is a change of the vessel: forgetting follows it.
    suspended_ = true;
    inconsistent_run_ = 0.0;
  }
  return changed;
}

void ConsistencyGuard::update_noise(const Mat2& At) {
  // The long-run variance density s_i of the equation error e_i = m_i - a_i q, from the
  // accepted windows: r = Y_i - Phi a_i has covariance s_i int h^2 z z^T, so r^T Z^-1 r / s_i
  // is chi-square with 2 degrees of freedom. The median (2 ln 2 of them) is robust to the
  // few windows a fault may have brought in; normalising by each window's own Z makes it
  // independent of the instruments' scale (a refreshed auxiliary model changes nothing).
  // Each window's statistic is kept in chi2_ (NaN: not accepted, or Z singular) for rejudge.
  // Nothing is computed again while neither the windows nor A^ have changed (the judgement
  // of the next window usually follows a rejudgement that changed nothing).
  if (noise_gen_ == gen_ && (At.array() == noise_At_.array()).all()) return;
  noise_gen_ = gen_;
  noise_At_ = At;
  noise_.setZero();
  chi2_.resize(windows_.size());
  for (int i = 0; i < 2; ++i) scratch_[i].clear();
  for (std::size_t j = 0; j < windows_.size(); ++j) {
    const GuardWindow& w = windows_[j];
    Vec2& x = chi2_[j];
    if (!w.accepted || !w.chi2(At, &x)) {
      x = Vec2(kNaN, kNaN);
      continue;
    }
    for (int i = 0; i < 2; ++i) scratch_[i].push_back(x(i));
  }
  if (static_cast<int>(scratch_[0].size()) < kMinBatches) return;
  for (int i = 0; i < 2; ++i) noise_(i) = median_in_place(&scratch_[i]) / (2.0 * M_LN2);
}

bool ConsistencyGuard::judge(const GuardWindow& w, Change* c) {
  // The window's equation-error sums r_i = int h z e_i = Y_i - Phi a^_i (a^_i: row i of the
  // memory's estimate) against what healthy data give: Var(r_i) = s_i (int h^2 z z^T + Phi_w
  // Phi^-1 Zw2 Phi^-T Phi_w^T), the window's noise plus the memory's uncertainty in a^_i, so
  // T = sum_i r_i^T Var(r_i)^-1 r_i is chi-square with 4 degrees of freedom on healthy
  // data. A sensor fault (bias, drift, scale, a noise burst, spikes) breaks m = A q by far
  // more: the window, and the data it covers, stay out of the memory.
  report_.consistent = true;
  report_.consistency = 0.0;
  Mat2 At;
  if (!s_.enabled || accepted_windows() < kMinJudge || !mem_.estimate(&At)) return true;
  update_noise(At);
  if (!(noise_.minCoeff() > 0)) return true;
  Mat2 K;  // Phi_w Phi^-1
  if (!solve(mem_.Phi.transpose(), w.Phi.transpose(), &K)) return true;
  K.transposeInPlace();
  const Mat2 S = w.Z + K * mem_.Zw2 * K.transpose();
  if (!(S.determinant() > 0)) return true;
  const Mat2 r = w.Y - w.Phi * At;
  const double T = weighted_chi2(S, r, noise_);
  // Materiality: how far the window would move A^ (rounding-level inconsistencies of exact
  // data move nothing).
  const bool ok = !(T > s_.threshold && relative_shift(mem_.Phi + w.Phi, r, At) > s_.min_shift);
  report_.consistent = ok;
  report_.consistency = T;
  if (!ok) {
    ++report_.rejected_windows;
    c->unsettled = true;
  }
  if (suspended_) {
    if (ok) suspended_ = false;  // the data agree with the memory again
    return true;
  }
  return ok;
}

bool ConsistencyGuard::rejudge(Change* c) {
  // Every accepted window whose data are still in the memory, against the memory itself
  // (in-sample, so Var(r_i) <= s_i Z: the test is conservative). The worst one beyond the
  // threshold leaves, and the memory is judged again without it, as long as one does: a
  // fault that came in before the guard could judge (the first kMinJudge windows, or right
  // after a reset) leaves once the healthy data outweigh it.
  if (!s_.enabled || suspended_) return false;
  bool removed = false;
  for (int iter = 0; iter < 8; ++iter) {
    Mat2 At;
    if (accepted_windows() < kMinJudge || !mem_.estimate(&At)) break;
    update_noise(At);
    if (!(noise_.minCoeff() > 0)) break;
    double worst = 0.0;
    int j_worst = -1;
    for (int j = 0; j < static_cast<int>(windows_.size()); ++j) {
      const GuardWindow& w = windows_[j];
      const Vec2& x = chi2_[static_cast<std::size_t>(j)];  // update_noise's, under this At
      if (std::isnan(x(0)) || !in_memory(w.seg0) || !in_memory(w.seg1)) continue;
      const double T = x(0) / noise_(0) + x(1) / noise_(1);
      if (T > worst) {
        worst = T;
        j_worst = j;
      }
    }
    if (j_worst < 0 || !(worst > s_.threshold)) break;
    const GuardWindow& w = windows_[j_worst];
    // The shift of A^ without it.
    const Mat2 r = w.Y - w.Phi * At;
    if (!(relative_shift(mem_.Phi - w.Phi, r, At) > s_.min_shift)) break;
    const std::uint64_t s0 = w.seg0, s1 = w.seg1;
    remove_segment(s0);
    remove_segment(s1);
    for (GuardWindow& v : windows_) {
      if (v.seg0 == s0 || v.seg1 == s0 || v.seg0 == s1 || v.seg1 == s1) v.accepted = false;
    }
    ++gen_;
    ++report_.removed_windows;
    c->unsettled = true;
    removed = true;
  }
  return removed;
}

bool ConsistencyGuard::check_memory(double t) {
  // Before convergence: the memory's estimate A_L against the estimate A_s of the windows of
  // the last recent_time alone (accepted or not). When the recent data agree among
  // themselves (no window beyond the threshold under A_s, with the noise level of their
  // own fit) and A_s differs from A_L by more than both estimates' uncertainties allow (a
  // Wald test, chi-square with 4 degrees of freedom when both describe the same vessel),
  // the memory is what is wrong: a fault in it from the start, or from before the guard
  // could judge, that the healthy data since cannot outweigh (the memory may even reject
  // them). It is rebuilt from the recent segments. Recent data that disagree among
  // themselves (a fault still in the recent span) change nothing.
  if (!s_.enabled || windows_.empty()) return false;
  Mat2 AtL;
  if (!mem_.estimate(&AtL)) return false;
  const double T_b = kBatchLength / s_.eps1;
  std::vector<const GuardWindow*> S;
  for (const GuardWindow& w : windows_) {
    if (w.t_end < t - s_.recent_time + 0.5 * T_b) continue;
    if (!final_segment(w.seg0) || !final_segment(w.seg1)) continue;
    if (!S.empty() && w.seg0 > S.back()->seg1) return false;  // a gap (restart) in the span
    S.push_back(&w);
  }
  const int needed = static_cast<int>(2.0 * s_.recent_time / T_b) - 2;
  if (static_cast<int>(S.size()) < std::max(needed, kMinJudge)) return false;
  Mat2 Phi = Mat2::Zero(), Y = Mat2::Zero(), Z = Mat2::Zero();
  for (const GuardWindow* w : S) {
    Phi += w->Phi;
    Y += w->Y;
    Z += w->Z;
  }
  Mat2 AtS;
  if (!solve(Phi, Y, &AtS)) return false;
  // The recent data's own noise level (robust: the median window) and their worst window.
  std::vector<double> q[2];
  for (const GuardWindow* w : S) {
    Vec2 x;
    if (!w->chi2(AtS, &x)) return false;
    for (int i = 0; i < 2; ++i) q[i].push_back(x(i));
  }
  Vec2 s2;
  for (int i = 0; i < 2; ++i) {
    std::vector<double> v = q[i];
    s2(i) = median_in_place(&v) / (2.0 * M_LN2);
  }
  if (!(s2.minCoeff() > 0)) return false;
  for (std::size_t k = 0; k < S.size(); ++k) {
    if (!(q[0][k] / s2(0) + q[1][k] / s2(1) <= s_.threshold)) return false;
  }
  // Wald test of A_s = A_L: Cov(row i) = s_i (Phi_s^-1 Z Phi_s^-T + Phi^-1 Zw2 Phi^-T).
  Mat2 C_s, C_l;
  if (!sandwich(Phi, Z, &C_s) || !sandwich(mem_.Phi, mem_.Zw2, &C_l)) return false;
  const Mat2 C = C_s + C_l;
  if (!(C.determinant() > 0)) return false;
  const double W = weighted_chi2(C, AtS - AtL, s2);
  report_.memory_mismatch = W;
  if (!(W > s_.threshold)) return false;
  // Rebuild the memory from the recent segments, oldest first.
  mem_ = KreisselmeierMemory{};
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
  for (GuardWindow& w : windows_) {
    w.accepted = w.seg0 >= first && final_segment(w.seg0) && final_segment(w.seg1);
    w.clock = clock_;
  }
  ++gen_;
  inconsistent_run_ = 0.0;
  ++report_.resets;
  return true;
}

void ConsistencyGuard::remove_segment(std::uint64_t id) {
  Stored& st = stored_[id % kStored];
  if (st.id != id || !st.in) return;
  mem_.remove(st.mem, std::exp(-s_.lambda * (clock_ - st.clock)));
  st.in = false;
}

}  // namespace usvfdi
