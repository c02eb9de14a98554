#include "breccia/mps/case_spec.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <cstdio>
#include <filesystem>

#include "breccia/common/error.hpp"
#include "breccia/common/yaml_input.hpp"

namespace breccia::mps {

double MaterialSpec::p_wave_speed() const {
  return std::sqrt((lame_lambda_pa + 2.0 * shear_modulus_pa) / density_kg_m3);
}
double MaterialSpec::s_wave_speed() const { return std::sqrt(shear_modulus_pa / density_kg_m3); }

namespace {

[[noreturn]] void fail(const Section& s, const std::string& key, const std::string& found,
                       const std::string& expected) {
  throw InputError(s.file(), s.field(key), found, expected);
}

std::string pascal_text(double v) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%g Pa", v);
  return buf;
}

LatticeSpec parse_lattice(const Section& s) {
  s.allow_only({"dimension", "box", "spacing", "thickness", "periodic"});
  LatticeSpec l;
  l.dimension = static_cast<int>(s.integer("dimension", 2));
  if (l.dimension != 2 && l.dimension != 3)
    fail(s, "dimension", std::to_string(l.dimension), "2 or 3");
  const auto box = s.numbers("box", Quantity::Length, l.dimension == 2 ? 4 : 6);
  for (int a = 0; a < l.dimension; ++a) {
    l.low_m[a] = box[a];
    l.high_m[a] = box[a + l.dimension];
    if (!(l.high_m[a] > l.low_m[a])) fail(s, "box", "upper corner not above lower corner", "[x0, y0, x1, y1] with x1 > x0, y1 > y0");
  }
  l.spacing_m = s.positive("spacing", Quantity::Length);
  l.thickness_m = s.positive("thickness", Quantity::Length, l.dimension == 2 ? l.spacing_m : 1.0);
  if (s.has("periodic")) {
    const YAML::Node n = s.node()["periodic"];
    if (!n.IsSequence() || n.size() != static_cast<size_t>(l.dimension))
      fail(s, "periodic", "not a list of " + std::to_string(l.dimension) + " booleans", "e.g. [true, false]");
    for (int a = 0; a < l.dimension; ++a) {
      try {
        l.periodic[a] = n[a].as<bool>();
      } catch (const YAML::Exception&) {
        fail(s, "periodic", "entry " + std::to_string(a) + " is not a boolean", "true or false");
      }
    }
  }
  return l;
}

MaterialSpec parse_material(const Section& s) {
  s.allow_only({"name", "density", "youngs_modulus", "poisson_ratio", "lambda", "mu", "C13", "C55", "plasticity", "fracture",
                "damping_ratio", "damping_frequency"});
  MaterialSpec m;
  m.name = s.text("name", "material");
  m.density_kg_m3 = s.positive("density", Quantity::Density);
  const bool engineering = s.has("youngs_modulus") || s.has("poisson_ratio");
  const bool lame = s.has("lambda") || s.has("mu");
  const bool stiffness = s.has("C13") || s.has("C55");
  if (engineering + lame + stiffness != 1)
    fail(s, "", "elastic constants given " + std::to_string(engineering + lame + stiffness) + " ways",
         "exactly one pair: youngs_modulus & poisson_ratio, lambda & mu, or C13 & C55");
  if (engineering) {
    const double e = s.positive("youngs_modulus", Quantity::Pressure);
    const double nu = s.number("poisson_ratio", Quantity::Dimensionless);
    if (!(nu > -1.0 && nu < 0.5)) fail(s, "poisson_ratio", std::to_string(nu), "-1 < nu < 0.5");
    const LameConstants l = lame_of_youngs(e, nu);  // plane strain in 2D
    m.lame_lambda_pa = l.lambda_pa;
    m.shear_modulus_pa = l.mu_pa;
  } else if (lame) {
    m.lame_lambda_pa = s.number("lambda", Quantity::Pressure);
    m.shear_modulus_pa = s.positive("mu", Quantity::Pressure);
  } else {
    m.lame_lambda_pa = s.number("C13", Quantity::Pressure);
    m.shear_modulus_pa = s.positive("C55", Quantity::Pressure);
  }
  if (!(m.lame_lambda_pa + 2.0 * m.shear_modulus_pa > 0))
    fail(s, lame ? "lambda" : "C13", "lambda + 2 mu is not positive", "a positive P-wave modulus");
  if (auto p = s.optional_section("plasticity")) {
    p->allow_only({"yield_stress", "hardening_modulus"});
    PlasticitySpec ps;
    if (!p->has("yield_stress")) fail(*p, "yield_stress", "missing", "the initial yield stress (> 0), e.g. 240 MPa");
    ps.yield_stress_pa = p->number("yield_stress", Quantity::Pressure);
    if (!(ps.yield_stress_pa > 0))
      fail(*p, "yield_stress", pascal_text(ps.yield_stress_pa), "a yield stress > 0");
    ps.hardening_modulus_pa = p->number("hardening_modulus", Quantity::Pressure, 0.0);
    if (!(ps.hardening_modulus_pa >= 0))
      fail(*p, "hardening_modulus", pascal_text(ps.hardening_modulus_pa),
           "a hardening modulus >= 0 (0: perfectly plastic)");
    m.plasticity = ps;
  }
  // Material damping (stress formulation): a damping ratio zeta at a frequency f, stored as
  // the stiffness-proportional (Rayleigh beta) coefficient beta = zeta / (pi f) (docs/mps.md).
  if (s.has("damping_ratio") || s.has("damping_frequency")) {
    if (!s.has("damping_ratio")) fail(s, "damping_ratio", "missing (damping_frequency is given)", "a damping ratio, e.g. 0.02");
    if (!s.has("damping_frequency"))
      fail(s, "damping_frequency", "missing (damping_ratio is given)", "the frequency the ratio holds at, e.g. 140 Hz");
    const double zeta = s.number("damping_ratio", Quantity::Dimensionless);
    if (!(zeta > 0.0 && zeta < 1.0)) fail(s, "damping_ratio", std::to_string(zeta), "a damping ratio 0 < zeta < 1");
    const double f = s.positive("damping_frequency", Quantity::Frequency);
    m.damping_ratio = zeta;
    m.damping_frequency_hz = f;
    m.viscous_time_s = zeta / (std::numbers::pi * f);
  }
  if (auto f = s.optional_section("fracture")) {
    f->allow_only({"tensile_strength"});
    if (!f->has("tensile_strength"))
      fail(*f, "tensile_strength", "missing", "the tensile strength (> 0) that the separation stress is compared with");
    FractureSpec fs;
    fs.tensile_strength_pa = f->number("tensile_strength", Quantity::Pressure);
    if (!(fs.tensile_strength_pa > 0))
      fail(*f, "tensile_strength", pascal_text(fs.tensile_strength_pa), "a tensile strength > 0");
    m.fracture = fs;
  }
  return m;
}

CrackSpec parse_crack(const Section& s, size_t index) {
  s.allow_only({"name", "segment", "static_friction", "kinetic_friction", "normal_stress", "stiffness_factor",
                "shear_stiffness", "normal_stiffness", "mode", "restick"});
  CrackSpec c;
  c.name = s.text("name", "crack" + std::to_string(index));
  if (!s.has("segment")) fail(s, "segment", "missing", "[[x0, y0], [x1, y1]]");
  const YAML::Node seg = s.node()["segment"];
  if (!seg.IsSequence() || seg.size() != 2) fail(s, "segment", "not a list of two points", "[[x0, y0], [x1, y1]]");
  for (int p = 0; p < 2; ++p) {
    YAML::Node wrapper;
    wrapper["point"] = seg[p];
    const auto v = Section(wrapper, s.file(), s.field("segment") + "[" + std::to_string(p) + "]").vec3("point", Quantity::Length);
    (p == 0 ? c.start_m : c.end_m) = v;
  }
  const double len = std::hypot(c.end_m[0] - c.start_m[0], c.end_m[1] - c.start_m[1]);
  if (!(len > 0)) fail(s, "segment", "has zero length", "two distinct end points");
  c.static_friction = s.number("static_friction", Quantity::Dimensionless);
  c.kinetic_friction = s.number("kinetic_friction", Quantity::Dimensionless, c.static_friction);
  if (c.static_friction < 0) fail(s, "static_friction", std::to_string(c.static_friction), "a coefficient >= 0");
  if (c.kinetic_friction < 0) fail(s, "kinetic_friction", std::to_string(c.kinetic_friction), "a coefficient >= 0");
  if (c.kinetic_friction > c.static_friction)
    fail(s, "kinetic_friction", "mu_k = " + std::to_string(c.kinetic_friction) + " > mu_s = " + std::to_string(c.static_friction),
         "kinetic friction <= static friction");
  c.normal_stress_pa = s.number("normal_stress", Quantity::Pressure, 0.0);
  if (c.normal_stress_pa < 0) fail(s, "normal_stress", std::to_string(c.normal_stress_pa), "a compressive pre-stress >= 0 (Pa)");
  c.stiffness_factor = s.positive("stiffness_factor", Quantity::Dimensionless, 1.0);
  if (s.has("shear_stiffness")) c.shear_stiffness_n_m = s.positive("shear_stiffness", Quantity::FractureEnergy);
  if (s.has("normal_stiffness")) c.normal_stiffness_n_m = s.positive("normal_stiffness", Quantity::FractureEnergy);
  c.clapping = s.choice("mode", {"sliding", "clapping"}, "sliding") == "clapping";
  c.restick_continuous = s.choice("restick", {"paper", "continuous"}, "paper") == "continuous";
  return c;
}

BoundarySpec parse_boundary(const Section& s, size_t index, int dimension) {
  s.allow_only({"name", "face", "box", "set", "components", "displacement"});
  BoundarySpec b;
  b.name = s.text("name", "boundary" + std::to_string(index));
  const int ways = s.has("face") + s.has("box") + s.has("set");
  if (ways != 1) fail(s, "", "particles selected " + std::to_string(ways) + " ways", "exactly one of face, box, set");
  if (s.has("face")) b.face = s.choice("face", {"left", "right", "bottom", "top", "back", "front"});
  if (s.has("set")) b.set = s.text("set");
  if (s.has("box")) {
    const auto v = s.numbers("box", Quantity::Length, dimension == 2 ? 4 : 6);
    std::array<double, 6> box{0, 0, -1e300, 0, 0, 1e300};
    for (int a = 0; a < dimension; ++a) {
      box[a] = v[a];
      box[3 + a] = v[a + dimension];
    }
    b.box_m = box;
  }
  const auto comps = s.texts("components");
  if (comps.empty()) fail(s, "components", "missing", "a list of prescribed components, e.g. [x]");
  for (const auto& c : comps) {
    if (c == "x") b.components[0] = true;
    else if (c == "y") b.components[1] = true;
    else if (c == "z" && dimension == 3) b.components[2] = true;
    else fail(s, "components", "'" + c + "'", dimension == 3 ? "x, y or z" : "x or y");
  }
  if (auto d = s.optional_section("displacement")) {
    d->allow_only({"type", "amplitude", "period", "frequency", "cycles", "delay", "window"});
    const std::string type = d->choice("type", {"sine_burst", "zero"}, "sine_burst");
    if (type == "sine_burst") {
      BurstHistory h;
      h.amplitude_m = d->number("amplitude", Quantity::Length);
      if (d->has("period") == d->has("frequency")) fail(*d, "period", "period and frequency both or neither given", "exactly one");
      h.period_s = d->has("period") ? d->positive("period", Quantity::Time) : 1.0 / d->positive("frequency", Quantity::Frequency);
      h.cycles = d->positive("cycles", Quantity::Dimensionless);
      h.delay_s = d->number("delay", Quantity::Time, 0.0);
      h.hann = d->choice("window", {"none", "hann"}, "none") == "hann";
      b.burst = h;
    }
  }
  return b;
}

InitialGaussian parse_initial_displacement(const Section& d) {
  d.allow_only({"type", "center", "width", "amplitude"});
  d.choice("type", {"gaussian"}, "gaussian");
  InitialGaussian g;
  g.center_m = d.vec3("center", Quantity::Length);
  g.width_m = d.positive("width", Quantity::Length);
  g.amplitude_m = d.vec3("amplitude", Quantity::Length);
  return g;
}

ProbeSpec parse_probe(const Section& s, size_t index) {
  s.allow_only({"name", "position", "field"});
  ProbeSpec p;
  p.name = s.text("name", "probe" + std::to_string(index));
  p.position_m = s.vec3("position", Quantity::Length);
  p.field = s.choice("field", {"displacement_x", "displacement_y", "displacement_z", "velocity_x", "velocity_y", "velocity_z"},
                     "displacement_x");
  return p;
}

bool inside_box(const LatticeSpec& l, const std::array<double, 3>& p) {
  const double tol = 1e-9 * l.spacing_m;
  for (int a = 0; a < l.dimension; ++a)
    if (p[a] < l.low_m[a] - tol || p[a] > l.high_m[a] + tol) return false;
  return true;
}

CaseSpec parse_root(const Section& root) {
  CaseSpec c;
  c.file = root.file();
  root.allow_only({"specimen", "model", "materials", "cracks", "boundary", "initial", "contact", "time", "output"});

  const Section spec = root.section("specimen");
  spec.allow_only({"lattice", "particles", "bodies"});
  if (spec.has("lattice") + spec.has("particles") + spec.has("bodies") != 1)
    fail(spec, "lattice", "lattice, particles, bodies: not exactly one given", "exactly one of lattice, particles, bodies");
  if (spec.has("bodies")) {
    c.bodies = parse_bodies(spec.section("bodies"));
  } else if (spec.has("lattice")) {
    c.lattice = parse_lattice(spec.section("lattice"));
  } else {
    c.particle_file = spec.input_path("particles");
  }
  const int dimension = c.lattice ? c.lattice->dimension : (c.bodies ? c.bodies->dimension : 2);

  const Section model = root.section("model");
  model.allow_only({"type", "re_over_spacing", "equation", "integrator", "formulation", "hourglass", "pressure_force",
                    "damping", "damping_until", "gravity", "lagrangian", "stencil_update_strain", "elastic_law"});
  model.choice("type", {"mps"});
  c.formulation = model.choice("formulation", {"displacement", "stress"}, "displacement") == "stress"
                      ? Formulation::Stress
                      : Formulation::Displacement;
  const bool stress = c.formulation == Formulation::Stress;
  // The stress formulation's stencils, contact and fracture are built on the open lattice: a
  // periodic axis was ignored there (a strip periodic in y read as free faces).
  if (stress && c.lattice && std::any_of(c.lattice->periodic.begin(), c.lattice->periodic.end(), [](bool p) { return p; }))
    fail(spec.section("lattice"), "periodic", "a periodic axis with the stress formulation",
         "periodic: false on every axis (periodic lattices: formulation: displacement)");
  for (const char* key :
       {"hourglass", "pressure_force", "damping", "damping_until", "gravity", "lagrangian", "stencil_update_strain",
        "elastic_law"})
    if (!stress && model.has(key)) fail(model, key, "given for the displacement formulation", "formulation: stress");
  if (!stress && c.bodies)
    fail(spec, "bodies", "several bodies in the displacement formulation (it has no contact)", "model.formulation: stress");
  if (stress && model.has("equation"))
    fail(model, "equation", "given for the stress formulation", "no equation key (it selects the displacement operator)");
  c.hourglass = model.number("hourglass", Quantity::Dimensionless, 0.1);
  if (!(c.hourglass >= 0 && c.hourglass <= 10)) fail(model, "hourglass", std::to_string(c.hourglass), "0 <= hourglass <= 10");
  c.repulsive_pressure = model.choice("pressure_force", {"conservative", "repulsive"}, "conservative") == "repulsive";
  c.updated_lagrangian = model.choice("lagrangian", {"total", "updated"}, "total") == "updated";
  c.stencil_update_strain = model.positive("stencil_update_strain", Quantity::Dimensionless, 0.1);
  if (c.stencil_update_strain > 1.0)
    fail(model, "stencil_update_strain", std::to_string(c.stencil_update_strain), "0 < stencil_update_strain <= 1");
  if (model.has("stencil_update_strain") && !c.updated_lagrangian)
    fail(model, "stencil_update_strain", "given with total Lagrangian stencils", "lagrangian: updated");
  c.damping_per_s = model.number("damping", Quantity::Frequency, 0.0);
  if (!(c.damping_per_s >= 0)) fail(model, "damping", std::to_string(c.damping_per_s), "a damping rate >= 0 (1/s)");
  if (model.has("damping_until")) {
    // Damping for a settling phase only (a body brought to rest under gravity before the
    // ground moves: mass damping acts on absolute velocities, so it must end by then).
    if (!model.has("damping")) fail(model, "damping_until", "given without damping", "damping: RATE as well");
    c.damping_until_s = model.positive("damping_until", Quantity::Time);
  }
  if (model.has("gravity")) c.gravity_m_s2 = model.vec3("gravity", Quantity::Acceleration);
  c.re_over_spacing = model.positive("re_over_spacing", Quantity::Dimensionless, 2.1);
  if (c.re_over_spacing < 1.01 || c.re_over_spacing > 5.0)
    fail(model, "re_over_spacing", std::to_string(c.re_over_spacing), "1.01 <= re/spacing <= 5 (nearest neighbours inside re)");
  c.equation = model.choice("equation", {"navier", "rotation_free"}, "navier") == "navier" ? Equation::Navier
                                                                                        : Equation::RotationFree;
  c.integrator = model.choice("integrator", {"symplectic_euler", "velocity_verlet"}, "symplectic_euler") ==
                         "symplectic_euler"
                     ? Integrator::SymplecticEuler
                     : Integrator::VelocityVerlet;
  if (stress && c.integrator != Integrator::SymplecticEuler)
    fail(model, "integrator", "velocity_verlet with the stress formulation", "symplectic_euler (the paper's scheme)");

  const auto materials = root.list("materials");
  if (materials.size() != 1)
    throw InputError(root.file(), "materials", std::to_string(materials.size()) + " materials",
                     "exactly one material (the MPS solver is single-material)");
  c.material = parse_material(materials[0]);
  if (c.material.fracture && !stress)
    fail(materials[0], "fracture", "given for the displacement formulation (it has no stress state)",
         "model.formulation: stress");
  if (c.material.fracture && c.updated_lagrangian)  // a rebuild would reconnect cut bonds
    fail(materials[0], "fracture", "given with model.lagrangian: updated (rebuilt stencils would rejoin cracks)",
         "model.lagrangian: total");
  if (c.material.plasticity && !stress)
    fail(materials[0], "plasticity", "given for the displacement formulation (it has no stress state)",
         "model.formulation: stress");
  // The elastic law from F needs F to hold the whole deformation: plastic flow and rebuilt
  // stencils keep the rate law (docs/mps.md, "Elastic law").
  const bool rate_needed = c.material.plasticity || c.updated_lagrangian;
  // Fracture defaults to the rate law too (allowed either way): a cut keeps the particle's
  // stress and re-measures its gradient on the cut stencil (solid_fracture.cpp), which the
  // rate law carries across, while the law from F jumps to the cut stencil's F at once. On
  // cases/mps-ring-impact the neo-Hookean law failed 1.6-2.6 times the particles and closed the
  // energy balance worse (docs/mps.md, "Elastic law").
  const bool rate_default = rate_needed || c.material.fracture.has_value();
  const std::string elastic_law = model.choice("elastic_law", {"neo_hookean", "rate"}, rate_default ? "rate" : "neo_hookean");
  if (elastic_law == "neo_hookean" && rate_needed)
    fail(model, "elastic_law",
         std::string("neo_hookean with ") + (c.material.plasticity ? "materials[0].plasticity" : "lagrangian: updated"),
         "elastic_law: rate (plastic flow and rebuilt stencils use the rate law), or no elastic_law key");
  c.rate_elastic_law = elastic_law == "rate";
  if (c.material.viscous_time_s > 0.0 && !stress)
    fail(materials[0], "damping_ratio", "given for the displacement formulation (material damping acts on the stress)",
         "model.formulation: stress (or model.damping for mass damping)");

  const auto cracks = root.list("cracks");
  for (size_t i = 0; i < cracks.size(); ++i) {
    if (stress) fail(cracks[i], "segment", "a frictional crack in the stress formulation", "cracks with formulation: displacement");
    c.cracks.push_back(parse_crack(cracks[i], i));
    if (dimension != 2) fail(cracks[i], "segment", "crack in a 3D model", "cracks in 2D models only");
    if (c.lattice && (!inside_box(*c.lattice, c.cracks.back().start_m) || !inside_box(*c.lattice, c.cracks.back().end_m)))
      fail(cracks[i], "segment", "end point outside the body", "a segment inside the lattice box");
  }
  const auto boundary = root.list("boundary");
  for (size_t i = 0; i < boundary.size(); ++i) c.boundary.push_back(parse_boundary(boundary[i], i, dimension));
  if (auto init = root.optional_section("initial")) {
    init->allow_only({"displacement", "velocity"});
    if (init->has("displacement")) c.initial = parse_initial_displacement(init->section("displacement"));
    if (init->has("velocity")) c.initial_velocity_m_s = init->vec3("velocity", Quantity::Velocity);
  }
  if (auto contact = root.optional_section("contact")) {
    contact->allow_only({"floor", "particles", "rigid_bodies"});
    if (!stress) fail(*contact, "floor", "contact in the displacement formulation", "formulation: stress");
    if (contact->has("particles")) c.particle_contact = parse_particle_contact(contact->section("particles"));
    const auto rigid = contact->list("rigid_bodies");
    for (size_t k = 0; k < rigid.size(); ++k) c.rigid_bodies.push_back(parse_rigid_body(rigid[k], k, dimension));
  }
  if (auto contact = root.optional_section("contact"); contact && contact->has("floor")) {
    const Section f = contact->section("floor");
    std::vector<std::string> floor_keys{"point", "normal", "stiffness_factor", "motion"};
    for (const auto& k : friction_keys()) floor_keys.push_back(k);
    f.allow_only(floor_keys);
    FloorSpec fs;
    fs.friction = parse_friction(f);
    fs.point_m = f.vec3("point", Quantity::Length);
    fs.normal = f.has("normal") ? f.vec3("normal", Quantity::Dimensionless) : std::array<double, 3>{0.0, 1.0, 0.0};
    if (!(std::hypot(fs.normal[0], fs.normal[1], fs.normal[2]) > 0)) fail(f, "normal", "a zero vector", "a nonzero normal");
    if (dimension == 2 && fs.normal[2] != 0.0)
      fail(f, "normal", "a z component in a 2D case (it weakened the penalty)", "an in-plane normal [x, y]");
    fs.stiffness_factor = f.positive("stiffness_factor", Quantity::Dimensionless, 1.0);
    if (f.has("motion")) fs.motion = parse_motion(f.section("motion"), dimension);
    c.floor = fs;
  }

  const Section time = root.section("time");
  time.allow_only({"end", "dt", "safety"});
  c.end_time_s = time.positive("end", Quantity::Time);
  if (time.has("dt")) c.dt_s = time.positive("dt", Quantity::Time);
  c.safety = time.positive("safety", Quantity::Dimensionless, stress ? 0.3 : 0.5);
  if (c.safety > 1.0) fail(time, "safety", std::to_string(c.safety), "0 < safety <= 1");

  if (auto out = root.optional_section("output")) {
    out->allow_only({"every", "history_every", "energy", "progress", "probes"});
    c.snapshot_every = out->integer("every", 0);
    c.history_every = out->integer("history_every", 1);
    if (c.snapshot_every < 0) fail(*out, "every", std::to_string(c.snapshot_every), "steps >= 0");
    if (c.history_every < 1) fail(*out, "history_every", std::to_string(c.history_every), "steps >= 1");
    c.energy = out->boolean("energy", false);
    c.progress = out->boolean("progress", true);
    const auto probes = out->list("probes");
    for (size_t i = 0; i < probes.size(); ++i) c.probes.push_back(parse_probe(probes[i], i));
  }
  return c;
}

}  // namespace

CaseSpec load_case(const std::string& case_file) { return parse_root(Section::load_file(case_file)); }

CaseSpec parse_case_text(const std::string& yaml_text, const std::string& name) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    throw InputError(name, "line " + std::to_string(e.mark.line + 1), "YAML syntax error: " + e.msg, "valid YAML");
  }
  return parse_root(Section(root, name, ""));
}

}  // namespace breccia::mps
