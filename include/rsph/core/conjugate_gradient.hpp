#pragma once
// Matrix-free preconditioned conjugate gradients for symmetric positive (semi-)definite systems A x = b.
#include "rsph/core/parallel.hpp"

#include <cmath>
#include <cstddef>
#include <functional>
#include <vector>

namespace rsph {

struct CgResult {
  int iterations = 0;
  double relative_residual = 0.0;  ///< |b - A x| / |b| at exit (0 when b = 0)
  bool converged = false;
};

/// Solves A x = b from the given x (a warm start) with the Jacobi preconditioner 1 / diagonal[i].
/// `apply(x, y)` sets y = A x. A singular A is fine when b lies in its range (b orthogonal to its null
/// space). Stops when |r| <= tolerance |b| or after max_iterations. `total(s)` completes a dot product's partial
/// sum: on many ranks, each holding some rows, the sum over them (the same on every rank, so all stop together).
template <class Apply, class Total = std::identity>
CgResult conjugate_gradient(Apply&& apply, const std::vector<double>& diagonal, const std::vector<double>& b,
                            std::vector<double>& x, double tolerance, int max_iterations, Total&& total = {}) {
  const std::size_t n = b.size();
  x.resize(n, 0.0);
  auto dot = [n, &total](const std::vector<double>& u, const std::vector<double>& v) {
    double s = 0.0;
#pragma omp parallel for reduction(+ : s) schedule(static) if (n >= kParallelMin)
    for (std::size_t i = 0; i < n; ++i) s += u[i] * v[i];
    return static_cast<double>(total(s));
  };
  CgResult out;
  const double b_norm = std::sqrt(dot(b, b));
  if (b_norm == 0.0) {
    x.assign(n, 0.0);
    out.converged = true;
    return out;
  }
  std::vector<double> r(n), z(n), d(n), q(n);
  apply(x, q);
  for (std::size_t i = 0; i < n; ++i) r[i] = b[i] - q[i];
  auto precondition = [&] {
    for (std::size_t i = 0; i < n; ++i) z[i] = diagonal[i] > 0.0 ? r[i] / diagonal[i] : r[i];
  };
  precondition();
  d = z;
  double rz = dot(r, z);
  double r_norm = std::sqrt(dot(r, r));
  while (r_norm > tolerance * b_norm && out.iterations < max_iterations) {
    apply(d, q);
    const double dq = dot(d, q);
    if (!(dq > 0.0)) break;  // the residual left is in A's null space
    const double alpha = rz / dq;
    for (std::size_t i = 0; i < n; ++i) {
      x[i] += alpha * d[i];
      r[i] -= alpha * q[i];
    }
    precondition();
    const double rz_next = dot(r, z);
    const double beta = rz_next / rz;
    rz = rz_next;
    for (std::size_t i = 0; i < n; ++i) d[i] = z[i] + beta * d[i];
    r_norm = std::sqrt(dot(r, r));
    ++out.iterations;
  }
  out.relative_residual = r_norm / b_norm;
  out.converged = r_norm <= tolerance * b_norm;
  return out;
}

}  // namespace rsph
