#pragma once
// Matrix-free preconditioned conjugate gradients for symmetric positive (semi-)definite systems A x = b.
#include "rsph/core/parallel.hpp"

#include <array>
#include <cmath>
#include <cstddef>
#include <span>
#include <vector>

namespace rsph {

/// One process's dot products are complete.
struct NoTotal {
  void operator()(std::span<double>) const {}
};

struct CgResult {
  int iterations = 0;
  double relative_residual = 0.0;  ///< |b - A x| / |b| at exit (0 when b = 0)
  bool converged = false;
};

/// Solves A x = b from the given x (a warm start) with the Jacobi preconditioner 1 / diagonal[i].
/// `apply(x, y)` sets y = A x. A singular A is fine when b lies in its range (b orthogonal to its null
/// space). Stops when |r| <= tolerance |b| or after max_iterations. `total(sums)` completes dot products' partial
/// sums in place: on many ranks, each holding some rows, the sums over them (the same on every rank, so all stop
/// together). The dot products needed at once are completed together, two a step: on many ranks a step's latency
/// is its reductions'.
template <class Apply, class Total = NoTotal>
CgResult conjugate_gradient(Apply&& apply, const std::vector<double>& diagonal, const std::vector<double>& b,
                            std::vector<double>& x, double tolerance, int max_iterations, Total&& total = {}) {
  const std::size_t n = b.size();
  x.resize(n, 0.0);
  auto partial = [n](const std::vector<double>& u, const std::vector<double>& v) {
    double s = 0.0;
#pragma omp parallel for reduction(+ : s) schedule(static) if (n >= kParallelMin)
    for (std::size_t i = 0; i < n; ++i) s += u[i] * v[i];
    return s;
  };
  CgResult out;
  std::vector<double> r(n), z(n), d(n), q(n);
  apply(x, q);  // before b's norm is known: on many ranks every rank takes part in every exchange apply makes
  for (std::size_t i = 0; i < n; ++i) r[i] = b[i] - q[i];
  auto precondition = [&] {
    for (std::size_t i = 0; i < n; ++i) z[i] = diagonal[i] > 0.0 ? r[i] / diagonal[i] : r[i];
  };
  precondition();
  std::array<double, 3> first{partial(b, b), partial(r, z), partial(r, r)};
  total(std::span<double>(first));
  const double b_norm = std::sqrt(first[0]);
  if (b_norm == 0.0) {
    x.assign(n, 0.0);
    out.converged = true;
    return out;
  }
  d = z;
  double rz = first[1];
  double r_norm = std::sqrt(first[2]);
  while (r_norm > tolerance * b_norm && out.iterations < max_iterations) {
    apply(d, q);
    std::array<double, 1> dq{partial(d, q)};
    total(std::span<double>(dq));
    if (!(dq[0] > 0.0)) break;  // the residual left is in A's null space
    const double alpha = rz / dq[0];
    for (std::size_t i = 0; i < n; ++i) {
      x[i] += alpha * d[i];
      r[i] -= alpha * q[i];
    }
    precondition();
    std::array<double, 2> next{partial(r, z), partial(r, r)};
    total(std::span<double>(next));
    const double beta = next[0] / rz;
    rz = next[0];
    for (std::size_t i = 0; i < n; ++i) d[i] = z[i] + beta * d[i];
    r_norm = std::sqrt(next[1]);
    ++out.iterations;
  }
  out.relative_residual = r_norm / b_norm;
  out.converged = r_norm <= tolerance * b_norm;
  return out;
}

}  // namespace rsph
