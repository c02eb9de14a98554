#include "breccia/solver/results_layout.hpp"

#include <cstdio>
#include <sstream>

#include "breccia/common/output_file.hpp"
#include "breccia/common/xdmf.hpp"

namespace breccia::solver {

std::string results_output_group(int index) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "/output/%06d", index);
  return buf;
}

void write_results_identity(const h5::File& f, const ResultsIdentity& id) {
  f.set_attr("/", "format", std::string("breccia-results"));
  f.set_attr("/", "format_version", kResultsFormatVersion);
  f.set_attr("/", "particles_file", id.particles_file);
  f.set_attr("/", "particles_content_id", id.particles_content_id);
  f.set_attr("/", "dimension", static_cast<long long>(id.dimension));
  f.set_attr("/", "thickness_m", id.thickness_m);
  f.set_attr("/", "model", id.model);
  f.set_attr("/", "case_file", id.case_file);
  f.set_attr("/", "complete", 0LL);
  f.set_attr("/", "output_count", 0LL);
}

std::string write_particles_beside_results(const std::string& out_dir, const ParticleModel& model) {
  const std::string path = out_dir + "/particles.h5";
  write_particle_file(path, model);
  return path;
}

void write_results_bonds(const h5::File& f, const HalfBondList& bonds) {
  f.write("/bonds/offsets", bonds.offsets, {bonds.offsets.size()});
  // Packed by scale-offset, not deflated: the list is the largest array of the file and both
  // ends of the chain wait for it (h5.hpp, Filter).
  f.write("/bonds/neighbors", bonds.neighbors, {bonds.neighbors.size()}, h5::Filter::ScaleOffset);
  f.write("/bonds/within_horizon", bonds.within_horizon, {bonds.within_horizon.size()});
}

void finish_results_output(const h5::File& f, int index, long long step, double time_s,
                           const std::vector<uint8_t>& broken, int64_t broken_count) {
  f.write(results_output_group(index) + "/broken", broken, {broken.size()});
  finish_results_output_attributes(f, index, step, time_s, broken_count);
}

void finish_results_output_attributes(const h5::File& f, int index, long long step, double time_s,
                                      int64_t broken_count) {
  const std::string g = results_output_group(index);
  f.set_attr(g, "broken_count", static_cast<long long>(broken_count));
  f.set_attr(g, "step", step);
  f.set_attr(g, "time_s", time_s);
  f.set_attr("/", "output_count", static_cast<long long>(index + 1));
  f.flush();
}

void write_results_xdmf(const std::string& path, size_t n, const std::vector<double>& times,
                        const std::vector<XdmfField>& fields) {
  std::ostringstream x;
  // The times to 17 digits, each the double of its group's time_s (6 digits made two outputs
  // 3e-7 s apart of a 0.6 s run one time, and differed from the .pvd files' times).
  x.precision(17);
  x << xdmf_document_begin() << "  <Grid Name=\"results\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
  auto item = [&](const std::string& dataset, int components, bool integer) {
    return xdmf_data_item(xdmf_dimensions(n, components), integer, integer ? 4 : 8, "results.h5:" + dataset);
  };
  for (size_t k = 0; k < times.size(); ++k) {
    const std::string g = results_output_group(static_cast<int>(k));
    x << "   <Grid Name=\"step" << k << "\" GridType=\"Uniform\">\n"
      << "    <Time Value=\"" << times[k] << "\"/>\n"
      << "    " << xdmf_polyvertex_topology(n) << "\n"
      << "    <Geometry GeometryType=\"XYZ\">" << item("/particles/position", 3, false) << "</Geometry>\n";
    for (const XdmfField& v : fields)
      x << "    " << xdmf_attribute_begin(v.name, xdmf_attribute_type(v.components), "Node")
        << item(g + "/" + v.name, v.components, v.integer) << "</Attribute>\n";
    x << "   </Grid>\n";
  }
  x << "  </Grid>\n" << xdmf_document_end();
  write_text_file(path, x.str());
}

}  // namespace breccia::solver
