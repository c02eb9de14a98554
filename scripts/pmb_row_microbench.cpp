// A stand-alone copy of the PMB packed row (4 lanes, AVX) on a 41^3 lattice, to cost what
// bounds it (docs/performance-log.md, "The packed rows 4 wide, four partial sums"). Not part of the
// solver. Build and run (CPU time per entry, 20 passes):
//   g++ -O3 -mavx -ffp-contract=off -fno-math-errno -fno-trapping-math -o /tmp/mb scripts/pmb_row_microbench.cpp
//   for v in 0 1 2 3 4 5; do /tmp/mb $v; done
// 0: the solver's entry (sqrt, division), sums in one chain per component, entry order
// 1: reciprocal square root by a bit seed and 4 Newton steps, one division by |xi|
// 2: the same on xi^2 r^2 (no division, no square root: 1 / (|xi| |xi + eta|) directly)
// 3: no square root nor division (r^2 - xi^2): the loop without the divider
// 4: as 0, the row's terms summed as a tree of one sum (no ordered chains)
// 5: as 0, four partial sums per component (entry q to sum q mod 4)
#include <immintrin.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <vector>
typedef double P __attribute__((vector_size(32)));
typedef long long PI __attribute__((vector_size(32)));
static inline P ld(const double* s) { P v; std::memcpy(&v, s, 32); return v; }
static inline P gat(const double* a, const int32_t* j, int c) {
  return P{a[3 * (int64_t)j[0] + c], a[3 * (int64_t)j[1] + c], a[3 * (int64_t)j[2] + c], a[3 * (int64_t)j[3] + c]};
}
static inline P sq(P v) { return (P)_mm256_sqrt_pd((__m256d)v); }
static inline P wid(const float* s) { return (P)_mm256_cvtps_pd(_mm_loadu_ps(s)); }
static inline P rsqrt_newton(P a) {  // seed 0x5fe6eb50c7b537a9 - bits/2 (3.4 % error), 4 Newton steps
  PI bits;
  std::memcpy(&bits, &a, 32);
  const long long m = 0x5fe6eb50c7b537a9LL;
  PI sb = (PI){m, m, m, m} - (bits >> 1);
  P y;
  std::memcpy(&y, &sb, 32);
  const P h = a * 0.5;
  for (int it = 0; it < 4; ++it) y = y * (1.5 - h * y * y);
  return y;
}
template <int variant>
void run() {
  const int n = 41;
  const double dx = 5e-4;
  const int N = n * n * n;
  std::vector<double> x(3 * N), x0(3 * N);
  for (int a = 0; a < n; ++a)
    for (int b = 0; b < n; ++b)
      for (int c = 0; c < n; ++c) {
        const int i = (a * n + b) * n + c;
        x0[3 * i] = a * dx; x0[3 * i + 1] = b * dx; x0[3 * i + 2] = c * dx;
      }
  for (int i = 0; i < 3 * N; ++i) x[i] = x0[i] * (1 + 1e-4) + 1e-9 * ((i * 7919) % 13);
  std::vector<int64_t> off{0};
  std::vector<int32_t> nb;
  std::vector<double> xi, kk;
  std::vector<float> s0;
  for (int a = 0; a < n; ++a)  // lattice neighbours within 3.38 dx: 155 per particle, about the bench's 162
    for (int b = 0; b < n; ++b)
      for (int c = 0; c < n; ++c) {
        const int i = (a * n + b) * n + c;
        for (int p = -4; p <= 4; ++p)
          for (int q = -4; q <= 4; ++q)
            for (int r = -4; r <= 4; ++r) {
              const double d2 = p * p + q * q + r * r;
              if (d2 == 0 || d2 > 3.38 * 3.38) continue;
              const int A = a + p, B = b + q, C = c + r;
              if (A < 0 || B < 0 || C < 0 || A >= n || B >= n || C >= n) continue;
              const int j = (A * n + B) * n + C;
              nb.push_back(j);
              const double ex = x0[3 * j] - x0[3 * i], ey = x0[3 * j + 1] - x0[3 * i + 1], ez = x0[3 * j + 2] - x0[3 * i + 2];
              xi.push_back(std::sqrt(ex * ex + ey * ey + ez * ez));
              kk.push_back(1e15);
              s0.push_back(1e-2f);
            }
        off.push_back(nb.size());
      }
  nb.resize(nb.size() + 8); xi.resize(xi.size() + 8, 1.0); kk.resize(kk.size() + 8); s0.resize(s0.size() + 8);
  std::vector<double> F(3 * N);
  const std::clock_t t0 = std::clock();
  const int passes = 20;
  long long over_rows = 0;
  for (int pass = 0; pass < passes; ++pass)
    for (int i = 0; i < N; ++i) {
      const double px = x[3 * i], py = x[3 * i + 1], pz = x[3 * i + 2];
      double fx = 0, fy = 0, fz = 0;
      P ax = {}, ay = {}, az = {};
      PI over_any = {};
      for (int64_t k = off[i]; k < off[i + 1]; k += 4) {  // (a row's last pack runs into the next row: a cost model)
        const int32_t* j = &nb[k];
        const P ddx = gat(x.data(), j, 0) - px, ddy = gat(x.data(), j, 1) - py, ddz = gat(x.data(), j, 2) - pz;
        const P r2 = ddx * ddx + ddy * ddy + ddz * ddz, X = ld(&xi[k]), K = ld(&kk[k]), S = wid(&s0[k]), k2 = K + K;
        P f;
        if constexpr (variant == 0 || variant == 4 || variant == 5) {
          const P len = sq(r2), e = len - X;
          over_any |= (e > S * X);
          f = k2 * e / (X * len);
        } else if constexpr (variant == 1) {
          const P y = rsqrt_newton(r2), len = r2 * y, e = len - X;
          over_any |= (e > S * X);
          f = k2 * e * y / X;
        } else if constexpr (variant == 2) {
          const P q = rsqrt_newton(X * X * r2), len = X * r2 * q, e = len - X;
          over_any |= (e > S * X);
          f = k2 * e * q;
        } else {
          const P e = r2 - X * X;
          over_any |= (e > S * X);
          f = k2 * e;
        }
        if constexpr (variant == 4) {
          fx += (f[0] + f[1]) + (f[2] + f[3]);
        } else if constexpr (variant == 5) {
          ax += f * ddx; ay += f * ddy; az += f * ddz;
        } else {
          const P cx = f * ddx, cy = f * ddy, cz = f * ddz;
          for (int l = 0; l < 4; ++l) { fx += cx[l]; fy += cy[l]; fz += cz[l]; }
        }
      }
      if constexpr (variant == 5) {
        fx = (ax[0] + ax[1]) + (ax[2] + ax[3]); fy = (ay[0] + ay[1]) + (ay[2] + ay[3]); fz = (az[0] + az[1]) + (az[2] + az[3]);
      }
      F[3 * i] = fx; F[3 * i + 1] = fy; F[3 * i + 2] = fz;
      over_rows += over_any[0] != 0;
    }
  const double t = double(std::clock() - t0) / CLOCKS_PER_SEC;
  std::printf("variant %d: %.3f ns/entry (CPU)  F[3000] = %.17g  rows over s0 %lld\n", variant, t / passes / off[N] * 1e9,
              F[3000], over_rows);
}
int main(int argc, char** argv) {
  switch (argc > 1 ? std::atoi(argv[1]) : 0) {
    case 1: run<1>(); break;
    case 2: run<2>(); break;
    case 3: run<3>(); break;
    case 4: run<4>(); break;
    case 5: run<5>(); break;
    default: run<0>();
  }
}
