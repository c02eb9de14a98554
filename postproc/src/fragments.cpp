#include "breccia/postproc/fragments.hpp"

#include <Eigen/Dense>
#include <array>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>

#include "cgal/oriented_box.hpp"

namespace breccia::postproc {

FragmentResult measure_fragments(const FragmentInputs& in, std::span<const int32_t> component,
                                 int32_t component_count, int64_t min_particles) {
  const size_t n = in.volume_m3.size();
  const int dim = in.dimension;
  FragmentResult r;
  r.component.assign(component.begin(), component.end());
  r.component_count = component_count;

  struct Acc {
    int64_t count = 0;
    double volume = 0, mass = 0, spacing_sum = 0;
    // x_sum by volume (the reference shape's centre and axes); xm_sum, u_sum, v_sum by mass
    // (the centre of mass now, which moves at the mass-weighted velocity).
    Eigen::Vector3d x_sum = Eigen::Vector3d::Zero(), xm_sum = Eigen::Vector3d::Zero(), u_sum = Eigen::Vector3d::Zero(),
                    v_sum = Eigen::Vector3d::Zero();
    Eigen::Matrix3d xx_sum = Eigen::Matrix3d::Zero();
  };
  std::vector<Acc> acc(component_count);
  auto vec = [](std::span<const double> a, size_t i) {
    return a.empty() ? Eigen::Vector3d::Zero().eval() : Eigen::Vector3d(a[3 * i], a[3 * i + 1], a[3 * i + 2]);
  };
  for (size_t i = 0; i < n; ++i) {
    Acc& a = acc[component[i]];
    const double v = in.volume_m3[i], m = v * in.density_kg_m3[i];
    const Eigen::Vector3d x = vec(in.position_m, i);
    ++a.count;
    a.volume += v;
    a.mass += m;
    a.spacing_sum += dim == 3 ? std::cbrt(v) : std::sqrt(v / in.thickness_m);
    a.x_sum += v * x;
    a.xm_sum += m * x;
    a.xx_sum += v * x * x.transpose();
    a.u_sum += m * vec(in.displacement_m, i);
    a.v_sum += m * vec(in.velocity_m_s, i);
  }

  // Principal axes from the volume-weighted covariance of the reference positions.
  std::vector<Eigen::Matrix3d> axes(component_count, Eigen::Matrix3d::Identity());
  // 3D: whether two principal moments are within kMomentsApart of each other, where the
  // principal axes are not determined and their box can be up to sqrt(2) too wide.
  constexpr double kMomentsApart = 0.25;
  std::vector<char> ambiguous_axes(component_count, 0);
  for (int32_t c = 0; c < component_count; ++c) {
    const Acc& a = acc[c];
    if (a.count < 2) continue;
    const Eigen::Vector3d mean = a.x_sum / a.volume;
    Eigen::Matrix3d cov = a.xx_sum / a.volume - mean * mean.transpose();
    if (dim == 2) {  // keep the axes in the plane
      cov.row(2).setZero();
      cov.col(2).setZero();
    }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov);
    axes[c] = es.eigenvectors();
    const Eigen::Vector3d moments = es.eigenvalues();  // ascending
    ambiguous_axes[c] = moments[1] - moments[0] <= kMomentsApart * moments[1] ||
                        moments[2] - moments[1] <= kMomentsApart * moments[2];
    if (dim == 2) {
      // The zero-variance z direction may land in any column: rebuild an in-plane pair.
      Eigen::Vector3d e = es.eigenvectors().col(2);
      e.z() = 0;
      if (e.norm() < 1e-12) e = Eigen::Vector3d::UnitX();
      e.normalize();
      axes[c].col(0) = e;
      axes[c].col(1) = Eigen::Vector3d(-e.y(), e.x(), 0);
      axes[c].col(2) = Eigen::Vector3d::UnitZ();
    }
  }
  std::vector<int32_t> kept;
  for (int32_t c = 0; c < component_count; ++c) {
    if (acc[c].count >= min_particles) {
      kept.push_back(c);
    } else {
      ++r.filtered_count;
      r.filtered_mass_kg += acc[c].mass;
    }
  }
  // The frame of CGAL's smallest box (3D: minimal volume; 2D: minimal area) of each kept
  // fragment; identity where the points span no volume (area), which the other two frames
  // then decide. The 3D search costs about 12 ms a fragment whatever its size (a fixed
  // evolutionary search), too much for the hundreds of thousands of debris fragments of a
  // pulverised block: it runs where the principal axes are not determined, on fragments of
  // at least kOrientedBoxMinParticles (smaller ones are at most about two spacings across,
  // where the box is mostly the spacing added to every edge). The 2D rectangle is exact and
  // cheap: always.
  constexpr int64_t kOrientedBoxMinParticles = 27;
  std::vector<Eigen::Matrix3d> oriented(component_count, Eigen::Matrix3d::Identity());
  {
    std::vector<int64_t> first(static_cast<size_t>(component_count) + 1, 0), member(n);
    for (size_t i = 0; i < n; ++i) ++first[static_cast<size_t>(component[i]) + 1];
    for (int32_t c = 0; c < component_count; ++c) first[c + 1] += first[c];
    std::vector<int64_t> next(first.begin(), first.end() - 1);
    for (size_t i = 0; i < n; ++i) member[static_cast<size_t>(next[component[i]]++)] = static_cast<int64_t>(i);
    const int64_t kept_count = static_cast<int64_t>(kept.size());
#pragma omp parallel for schedule(dynamic, 1)
    for (int64_t k = 0; k < kept_count; ++k) {
      const int32_t c = kept[static_cast<size_t>(k)];
      if (dim == 3 && (!ambiguous_axes[c] || acc[c].count < kOrientedBoxMinParticles)) continue;
      std::vector<double> xyz;
      xyz.reserve(3 * static_cast<size_t>(acc[c].count));
      for (int64_t m = first[c]; m < first[c + 1]; ++m) {
        const Eigen::Vector3d x = vec(in.position_m, static_cast<size_t>(member[m]));
        xyz.insert(xyz.end(), {x.x(), x.y(), dim == 2 ? 0.0 : x.z()});
      }
      if (const auto frame = oriented_box_frame(xyz, dim))
        oriented[c] = Eigen::Map<const Eigen::Matrix3d>(frame->data());  // column-major: columns are the axes
    }
  }
  // Three candidate frames per fragment: principal axes, coordinate axes and CGAL's oriented
  // box. Principal axes are arbitrary for near-isotropic shapes (a cube) and for shapes with
  // two equal moments (a square plate); keep the box whose middle edge (the sieve size) is
  // smallest: the orientation in which the fragment falls through.
  constexpr int kFrames = 3;
  const Eigen::Vector3d big = Eigen::Vector3d::Constant(1e300);
  std::vector<Eigen::Vector3d> lo[kFrames], hi[kFrames];
  for (int f = 0; f < kFrames; ++f) {
    lo[f].assign(component_count, big);
    hi[f].assign(component_count, -big);
  }
  for (size_t i = 0; i < n; ++i) {
    const int32_t c = component[i];
    const Eigen::Vector3d x = vec(in.position_m, i);
    const Eigen::Vector3d p = axes[c].transpose() * x;
    const Eigen::Vector3d o = oriented[c].transpose() * x;
    lo[0][c] = lo[0][c].cwiseMin(p);
    hi[0][c] = hi[0][c].cwiseMax(p);
    lo[1][c] = lo[1][c].cwiseMin(x);
    hi[1][c] = hi[1][c].cwiseMax(x);
    lo[2][c] = lo[2][c].cwiseMin(o);
    hi[2][c] = hi[2][c].cwiseMax(o);
  }
  std::stable_sort(kept.begin(), kept.end(), [&](int32_t a, int32_t b) { return acc[a].mass > acc[b].mass; });
  std::vector<int32_t> fragment_of_component(component_count, -1);
  for (size_t k = 0; k < kept.size(); ++k) {
    const int32_t c = kept[k];
    const Acc& a = acc[c];
    fragment_of_component[c] = static_cast<int32_t>(k);
    Fragment f;
    f.particle_count = a.count;
    f.volume_m3 = a.volume;
    f.mass_kg = a.mass;
    const Eigen::Vector3d xc = a.x_sum / a.volume;
    const Eigen::Vector3d cm = a.mass > 0 ? Eigen::Vector3d((a.xm_sum + a.u_sum) / a.mass) : xc;
    const Eigen::Vector3d vc = a.mass > 0 ? Eigen::Vector3d(a.v_sum / a.mass) : Eigen::Vector3d::Zero();
    for (int d = 0; d < 3; ++d) {
      f.centroid_reference_m[d] = xc[d];
      f.centroid_m[d] = cm[d];
      f.velocity_m_s[d] = vc[d];
    }
    f.equivalent_diameter_m = dim == 3 ? std::cbrt(6.0 * a.volume / std::numbers::pi)
                                       : std::sqrt(4.0 * a.volume / in.thickness_m / std::numbers::pi);
    const double mean_spacing = a.spacing_sum / a.count;
    const int edges = dim == 3 ? 3 : 2;
    std::array<double, 3> box{0, 0, 0};
    double best_sieve = 1e300;
    for (int frame = 0; frame < kFrames; ++frame) {
      std::array<double, 3> b{0, 0, 0};
      for (int d = 0; d < edges; ++d) b[d] = hi[frame][c][d] - lo[frame][c][d] + mean_spacing;
      std::sort(b.begin(), b.end(), std::greater<>());
      if (b[1] < best_sieve) {  // the orientation in which the fragment passes the finer sieve
        best_sieve = b[1];
        box = b;
      }
    }
    std::sort(box.begin(), box.end(), std::greater<>());
    f.box_m = box;
    f.sieve_size_m = box[1];
    r.fragments.push_back(f);
  }
  r.fragment_id.resize(n);
  for (size_t i = 0; i < n; ++i) r.fragment_id[i] = fragment_of_component[component[i]];
  return r;
}

}  // namespace breccia::postproc
