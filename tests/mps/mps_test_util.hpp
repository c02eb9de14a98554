#pragma once
// Helpers shared by the MPS tests: lattices, bond lists, a probe recorder.
#include <cmath>
#include <complex>
#include <cstdio>
#include <utility>
#include <numbers>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "breccia/common/error.hpp"
#include "breccia/mps/neighbours.hpp"
#include "breccia/mps/simulation.hpp"

namespace breccia::mps::test {

// Regular lattice of n[0] x n[1] (x n[2]) particles, spacing h, centred cells.
inline std::vector<double> lattice(int dimension, int nx, int ny, int nz, double h) {
  std::vector<double> p;
  for (int k = 0; k < (dimension == 3 ? nz : 1); ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        p.push_back((i + 0.5) * h);
        p.push_back((j + 0.5) * h);
        p.push_back(dimension == 3 ? (k + 0.5) * h : 0.0);
      }
  return p;
}

// `text` with the first occurrence of `from` replaced by `to`; a deck edit that finds
// nothing to replace fails the test instead of testing the unchanged deck.
inline std::string replace_once(std::string text, const std::string& from, const std::string& to) {
  const auto pos = text.find(from);
  EXPECT_NE(pos, std::string::npos) << from;
  return pos == std::string::npos ? text : text.replace(pos, from.size(), to);
}

// The message of the InputError that build() throws, or "" when it accepts its input.
template <class Build>
std::string input_error_of(Build build) {
  try {
    build();
  } catch (const breccia::InputError& e) {
    return e.what();
  }
  return "";
}

// Replace each "${KEY}" in text by its value (the standard library here has no <format>).
inline std::string fill(std::string text, const std::vector<std::pair<std::string, std::string>>& values) {
  for (const auto& [key, value] : values) {
    const std::string token = "${" + key + "}";
    for (size_t pos = text.find(token); pos != std::string::npos; pos = text.find(token, pos + value.size()))
      text.replace(pos, token.size(), value);
  }
  return text;
}
inline std::string num(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.12g", v);
  return buf;
}

// Run a simulation to its end time, recording `field` at the particle nearest `where`.
struct Trace {
  std::vector<double> t, value;
};
inline Trace run_and_record(Simulation& sim, const std::array<double, 3>& where, const std::string& field) {
  Trace tr;
  const int probe = sim.nearest_particle(where);
  const long long steps = static_cast<long long>(std::ceil(sim.spec().end_time_s / sim.dt_s() - 1e-9));
  tr.t.push_back(sim.time_s());
  tr.value.push_back(sim.sample(probe, field));
  for (long long s = 0; s < steps; ++s) {
    sim.step();
    tr.t.push_back(sim.time_s());
    tr.value.push_back(sim.sample(probe, field));
  }
  return tr;
}

// Amplitude of the n-th harmonic of frequency f over [t0, t1] (lock-in: the window holds
// an integer number of periods, so harmonics are orthogonal on it).
inline double harmonic_amplitude(const Trace& tr, double f, int n, double t0, double t1) {
  std::complex<double> acc = 0.0;
  double span = 0.0;
  for (size_t k = 1; k < tr.t.size(); ++k) {
    if (tr.t[k] < t0 || tr.t[k] > t1) continue;
    const double dt = tr.t[k] - tr.t[k - 1];
    acc += tr.value[k] * std::exp(std::complex<double>(0.0, -2.0 * std::numbers::pi * n * f * tr.t[k])) * dt;
    span += dt;
  }
  return 2.0 * std::abs(acc) / span;
}

}  // namespace breccia::mps::test
