#include "breccia/postproc/mps_history.hpp"

#include <array>

namespace breccia::postproc {
namespace {

void add_column(History& h, const std::string& name, std::vector<double> values) {
  h.names.push_back(name);
  h.columns.push_back(std::move(values));
}

// "<name>_displacement_x" -> probe "<name>", component "ux" (false when not a probe column).
bool probe_column(const std::string& column, std::string& probe, std::string& component) {
  static const std::array<std::pair<const char*, char>, 2> fields{{{"_displacement_", 'u'}, {"_velocity_", 'v'}}};
  for (const auto& [field, letter] : fields) {
    const std::string f = field;
    if (column.size() < f.size() + 2) continue;
    const size_t at = column.size() - f.size() - 1;
    const char axis = column.back();
    if (column.compare(at, f.size(), f) != 0 || (axis != 'x' && axis != 'y' && axis != 'z')) continue;
    probe = column.substr(0, at);
    component = std::string(1, letter) + axis;
    return true;
  }
  return false;
}

}  // namespace

MpsHistoryMapping map_mps_history(const History& mps) {
  MpsHistoryMapping m;
  m.history = mps;
  History& h = m.history;
  const size_t rows = mps.rows();
  for (size_t c = 0; c < mps.names.size(); ++c) {
    std::string probe, component;
    if (probe_column(mps.names[c], probe, component)) add_column(h, "probe_" + probe + "_" + component, mps.columns[c]);
  }
  auto column_or_zero = [&](const char* name) {
    const auto* c = mps.find(name);
    return c ? *c : std::vector<double>(rows, 0.0);
  };
  const auto* kinetic = mps.find("kinetic_energy_J");
  if (!kinetic) {
    m.notes.push_back("MPS history.csv has no energy columns (case output.energy: false): no energy balance");
    return m;
  }
  std::vector<double> strain(rows, 0.0), dissipated(rows, 0.0), external(rows, 0.0), gravity = column_or_zero("gravity_energy_J");
  if (mps.find("stress_work_J")) {
    // Stress formulation (solid.hpp): stress work = elastic energy + plastic dissipation, not
    // separable from the history; hourglass and contact penalties are stored energies.
    const auto work = mps.column("stress_work_J");
    const auto hourglass = column_or_zero("hourglass_energy_J"), contact = column_or_zero("contact_energy_J");
    for (size_t r = 0; r < rows; ++r) strain[r] = work[r] + hourglass[r] + contact[r];
    dissipated = column_or_zero("friction_dissipation_J");
    const auto viscous = column_or_zero("material_damping_J");  // materials[0].damping_ratio
    for (size_t r = 0; r < rows; ++r) dissipated[r] += viscous[r];
    m.terms = {{"kinetic_J", "kinetic_energy_J (particles and free rigid bodies)"},
               {"strain_J", "stress_work_J + hourglass_energy_J + contact_energy_J (stress work holds the plastic "
                            "dissipation too: MPS does not separate it from the elastic energy)"},
               {"dissipated_J", std::string(mps.find("friction_dissipation_J") ? "friction_dissipation_J (Coulomb slip)"
                                                                    : "0 (no friction_dissipation_J column: no frictional contact)") +
                                    (mps.find("material_damping_J") ? " + material_damping_J (viscous stress)" : "")},
               {"external_work_J", "initial kinetic + strain + dissipated (first row) - gravity_energy_J (work of gravity)"}};
    m.notes.push_back("MPS fracture is a strength criterion without a fracture energy: cut bonds release no recorded "
                      "energy, dissipated_J has no fracture part and G0 x crack area is not computed");
  } else {
    // Displacement formulation (simulation.hpp): elastic energy of eq. (6) + crack springs in stick.
    strain = column_or_zero("elastic_energy_J");
    m.terms = {{"kinetic_J", "kinetic_energy_J"},
               {"strain_J", "elastic_energy_J (continuum + crack springs in stick)"},
               {"dissipated_J", "0: the crack pairs' friction dissipation is not recorded by MPS"},
               {"external_work_J", "initial kinetic + strain (first row)"}};
    m.notes.push_back("MPS displacement formulation: the friction dissipation of slipping crack pairs is not recorded, "
                      "so the balance does not close while cracks slip");
  }
  m.notes.push_back("MPS does not record the work of prescribed boundary displacements: external_work_J is the initial "
                    "energy plus the work of gravity, and the balance closes only for runs loaded by initial velocity, "
                    "initial displacement, gravity or contact");
  const double initial = rows ? (*kinetic)[0] + strain[0] + dissipated[0] + gravity[0] : 0.0;
  for (size_t r = 0; r < rows; ++r) external[r] = initial - gravity[r];
  add_column(h, "kinetic_J", *kinetic);
  add_column(h, "strain_J", strain);
  add_column(h, "external_work_J", external);
  add_column(h, "dissipated_J", dissipated);
  m.energy = true;
  return m;
}

}  // namespace breccia::postproc
