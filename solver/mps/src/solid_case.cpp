#include "breccia/mps/solid_case.hpp"

#include <cmath>

#include "breccia/mps/contact_case.hpp"
#include "breccia/mps/particles.hpp"

namespace breccia::mps {

Solid make_solid(const CaseSpec& spec, std::string* content_id) {
  ParticleCloud cloud = build_particle_cloud(spec);
  if (content_id) *content_id = cloud.content_id;
  const std::vector<PrescribedSet> prescribed = select_boundary(spec, cloud);
  const MaterialSpec& m = spec.material;
  SolidLaw law;
  law.lame_lambda_pa = m.lame_lambda_pa;
  law.shear_modulus_pa = m.shear_modulus_pa;
  law.viscous_time_s = m.viscous_time_s;
  law.elastic = spec.rate_elastic_law ? ElasticLaw::Rate : ElasticLaw::NeoHookean;
  if (m.plasticity) {
    law.plastic = true;
    law.hardening = {m.shear_modulus_pa, m.plasticity->yield_stress_pa, m.plasticity->hardening_modulus_pa};
  }
  SolidOptions opt;
  opt.dimension = cloud.dimension;
  opt.spacing_m = cloud.spacing_m;
  opt.thickness_m = cloud.thickness_m;
  opt.re_over_spacing = spec.re_over_spacing;
  opt.hourglass = spec.hourglass;
  opt.updated_lagrangian = spec.updated_lagrangian;
  opt.stencil_update_strain = spec.stencil_update_strain;
  opt.damping_per_s = spec.damping_per_s;
  if (spec.damping_until_s) opt.damping_until_s = *spec.damping_until_s;
  opt.pressure = spec.repulsive_pressure ? PressureForce::Repulsive : PressureForce::Conservative;
  opt.safety = spec.safety;
  opt.dt_s = spec.dt_s;
  opt.gravity_m_s2 = spec.gravity_m_s2;
  opt.body_id = cloud.body_id;
  const std::vector<double> position = cloud.position_m;
  Solid solid(std::move(cloud.position_m), std::move(cloud.volume_m3), m.density_kg_m3, law, opt);
  if (m.fracture) solid.set_fracture({m.fracture->tensile_strength_pa});
  if (spec.floor) {
    const FloorSpec& fl = *spec.floor;
    solid.set_floor({fl.point_m, fl.normal, fl.stiffness_factor, fl.friction.static_friction,
                     fl.friction.kinetic_friction, fl.friction.tangential_stiffness_factor, fl.motion});
  }
  const size_t n = solid.size();
  for (int a = 0; a < solid.dimension(); ++a)
    for (size_t i = 0; i < n; ++i) solid.velocity(a)[i] = spec.initial_velocity_m_s[a];
  if (spec.initial) {
    const auto& g = *spec.initial;
    for (size_t i = 0; i < n; ++i) {
      double r2 = 0.0;
      for (int a = 0; a < solid.dimension(); ++a) r2 += std::pow(position[3 * i + a] - g.center_m[a], 2);
      const double f = std::exp(-r2 / (g.width_m * g.width_m));
      for (int a = 0; a < solid.dimension(); ++a) solid.displacement(a)[i] = g.amplitude_m[a] * f;
    }
  }
  configure_contact(spec, opt.body_id, solid);  // after the initial state: adds body velocities
  for (const auto& set : prescribed) solid.add_prescribed(set);
  return solid;
}

std::optional<DeviceRefusal> solid_device_refusal(const CaseSpec& spec) {
  const std::string cpu = " (or --backend cpu)";
  if (spec.updated_lagrangian)
    return DeviceRefusal{"model.lagrangian", "updated with --backend cuda", "total on the GPU" + cpu};
  if (spec.particle_contact && (spec.particle_contact->friction.static_friction > 0.0 ||
                                spec.particle_contact->friction.kinetic_friction > 0.0))
    return DeviceRefusal{"contact.particles.static_friction", "friction between particles with --backend cuda",
                         "frictionless particle contact on the GPU" + cpu};
  if (!spec.rigid_bodies.empty())
    return DeviceRefusal{"contact.rigid_bodies", "rigid polygons with --backend cuda", "none on the GPU" + cpu};
  if (spec.damping_until_s)
    return DeviceRefusal{"model.damping_until", "a settling phase with --backend cuda", "damping for the whole run on the GPU" + cpu};
  if (spec.material.viscous_time_s > 0.0)
    return DeviceRefusal{"materials[0].damping_ratio", "material damping with --backend cuda", "none on the GPU" + cpu};
  if (spec.floor && spec.floor->motion)
    return DeviceRefusal{"contact.floor.motion", "a moving floor with --backend cuda", "a fixed floor on the GPU" + cpu};
  return std::nullopt;
}

}  // namespace breccia::mps
