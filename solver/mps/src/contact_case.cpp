#include "breccia/mps/contact_case.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "breccia/common/error.hpp"
#include "breccia/common/units.hpp"

namespace breccia::mps {

void configure_contact(const CaseSpec& spec, const std::vector<int>& body_id, Solid& solid) {
  const size_t n = solid.size();
  if (spec.bodies) {
    for (size_t i = 0; i < n; ++i)
      for (int a = 0; a < solid.dimension(); ++a) solid.velocity(a)[i] += spec.bodies->shapes[body_id[i]].velocity_m_s[a];
  }
  // Particle contact: asked for, or implied by two or more bodies (which would otherwise
  // pass through each other).
  const bool several = spec.bodies && spec.bodies->shapes.size() > 1;
  if (spec.particle_contact || several) {
    const ParticleContactSpec pc = spec.particle_contact.value_or(ParticleContactSpec{});
    ParticleContact p;
    p.distance_m = pc.distance_factor * solid.spacing_m();
    p.stiffness_n_m = pc.stiffness_factor * solid.face_stiffness_n_m();
    p.normal = pc.normal == "pair" ? ContactNormal::Pair : ContactNormal::NeighbourDistribution;
    p.window_m = solid.spacing_m();
    p.tangential_stiffness_n_m = pc.friction.tangential_stiffness_factor * solid.shear_face_stiffness_n_m();
    p.static_friction = pc.friction.static_friction;
    p.kinetic_friction = pc.friction.kinetic_friction;
    p.body_id = body_id;
    solid.contact().set_particle_contact(std::move(p));
  }
  for (size_t k = 0; k < spec.rigid_bodies.size(); ++k) {
    const RigidBodySpec& r = spec.rigid_bodies[k];
    RigidPolygon p;
    p.name = r.name;
    p.x_m = r.x_m;
    p.y_m = r.y_m;
    p.fixed = r.fixed;
    const PolygonGeometry g = polygon_geometry(r.x_m, r.y_m);
    p.mass_kg = r.density_kg_m3 * g.area_m2 * solid.thickness_m();
    p.inertia_kg_m2 = r.density_kg_m3 * g.polar_moment_m4 * solid.thickness_m();
    p.velocity_m_s = {r.velocity_m_s[0], r.velocity_m_s[1]};
    p.angular_velocity_rad_s = r.angular_velocity_rad_s;
    // Per particle, one layer of the material (A / spacing), a stated length of it, or a
    // contact layer of the polygon's material: with the last two the stiffness per unit area
    // of a face stays the same when the spacing is refined.
    // (The products in this order: a stiffness_length's penalties as before it was added.)
    const double per_area = r.stiffness_length_m > 0.0 ? solid.spacing_m() / r.stiffness_length_m : 1.0;
    const double normal_n_m = r.contact_layer ? r.contact_layer->normal_stiffness_pa_m() * solid.face_area_m2()
                                              : solid.face_stiffness_n_m();
    const double tangential_n_m = r.contact_layer ? r.contact_layer->tangential_stiffness_pa_m() * solid.face_area_m2()
                                                  : solid.shear_face_stiffness_n_m();
    p.law.normal_stiffness_n_m = r.stiffness_factor * per_area * normal_n_m;
    p.law.tangential_stiffness_n_m = r.friction.tangential_stiffness_factor * per_area * tangential_n_m;
    if (r.contact_layer && n > 0) {
      // The penalty is stated, not tied to the spacing, so it can outrun the step: a particle
      // on it oscillates at omega = sqrt(k / m); the explicit step is stable for omega dt < 2
      // and its period resolved by 6 steps at omega dt = 1, the limit taken here.
      double lightest = solid.volume_m3()[0];
      for (size_t i = 1; i < n; ++i) lightest = std::min(lightest, solid.volume_m3()[i]);
      const double omega_dt = std::sqrt(p.law.normal_stiffness_n_m / (solid.density_kg_m3() * lightest)) * solid.dt_s();
      if (!(omega_dt <= 1.0))
        throw InputError(spec.file, "contact.rigid_bodies[" + std::to_string(k) + "].contact_layer.thickness",
                         "a layer stiff enough per unit area for omega dt = " + short_number(omega_dt) +
                             " per particle (omega = sqrt(k / m), dt " + short_number(solid.dt_s()) + " s)",
                         "omega dt <= 1: a thicker or softer layer, or a smaller time.safety");
    }
    p.law.static_friction = r.friction.static_friction;
    p.law.kinetic_friction = r.friction.kinetic_friction;
    p.law.damping_ratio = damping_ratio_of_restitution(r.restitution);
    p.floor_damping_ratio = damping_ratio_of_restitution(r.floor_restitution);
    p.motion = r.motion;
    long long inside = 0;
    for (size_t i = 0; i < n; ++i) {
      double normal[2];
      const double px = solid.position_m()[3 * i] + solid.displacement(0)[i];
      const double py = solid.position_m()[3 * i + 1] + solid.displacement(1)[i];
      inside += polygon_penetration(p.x_m.data(), p.y_m.data(), static_cast<int>(p.x_m.size()), px, py, normal) > 0.0;
    }
    if (inside > 0)
      throw InputError(spec.file, "contact.rigid_bodies[" + std::to_string(k) + "].vertices",
                       "polygon '" + r.name + "' holds " + std::to_string(inside) + " particle(s) at the start",
                       "a rigid body clear of the particles at t = 0");
    solid.contact().add_polygon(std::move(p));
  }
  // Polygon-polygon contact is frictionless (docs/mps.md): a free polygon resting on a moving
  // frictional fixed one is not carried along (found in review, 2026-12-08). Said, not refused:
  // the same friction acts on the particles that touch that polygon.
  const bool free_polygon = std::any_of(spec.rigid_bodies.begin(), spec.rigid_bodies.end(), [](const RigidBodySpec& r) { return !r.fixed; });
  for (size_t k = 0; k < spec.rigid_bodies.size() && free_polygon; ++k) {
    const RigidBodySpec& r = spec.rigid_bodies[k];
    if (r.fixed && r.motion && (r.friction.static_friction > 0.0 || r.friction.kinetic_friction > 0.0))
      std::fprintf(stderr,
                   "mps: warning: %s: contact.rigid_bodies[%zu] ('%s') moves and has friction, which acts on particles "
                   "only: polygon-polygon contact is frictionless, so a free polygon on it is not carried along\n",
                   spec.file.c_str(), k, r.name.c_str());
  }
  if (solid.contact().damped()) {  // the particle dashpots' m_eff: the particle masses
    std::vector<double> mass(n);
    for (size_t i = 0; i < n; ++i) mass[i] = solid.density_kg_m3() * solid.volume_m3()[i];
    solid.contact().set_particle_masses(std::move(mass));
  }
}

}  // namespace breccia::mps
