#include "breccia/postproc/post.hpp"

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <condition_variable>
#include <cstdlib>
#include <deque>
#include <exception>
#include <fstream>
#include <future>
#include <map>
#include <mutex>
#include <optional>
#include <span>
#include <sstream>
#include <thread>

#include <omp.h>

#include "breccia/common/data_dir.hpp"
#include "breccia/common/error.hpp"
#include "breccia/common/h5.hpp"
#include "breccia/common/json_file.hpp"
#include "breccia/common/output_file.hpp"
#include "breccia/common/progress.hpp"
#include "breccia/postproc/bond_graph.hpp"
#include "breccia/postproc/fragments.hpp"
#include "breccia/postproc/history.hpp"
#include "breccia/postproc/meshes.hpp"
#include "breccia/postproc/mps_history.hpp"
#include "breccia/postproc/run_data.hpp"
#include "breccia/postproc/size_distribution.hpp"
#include "breccia/postproc/spectrum.hpp"

namespace breccia::postproc {
namespace fs = std::filesystem;

// Installed as share/breccia/postproc/scripts (in the build tree: a link to postproc/scripts).
fs::path default_scripts_dir() { return data_path("BRECCIA_POSTPROC_SCRIPTS", "postproc/scripts"); }

namespace {

// --hann tapers a gate cut out of a longer record at both ends (symmetric Hann) and a whole
// record periodically (its DFT bins stay orthogonal); spectrum.hpp, Window.
Window spectrum_window(const PostOptions& o) {
  return !o.hann ? Window::Rectangular : o.gate_s ? Window::HannSymmetric : Window::Hann;
}

const char* window_name(Window w) {
  return w == Window::Rectangular ? "rectangular" : w == Window::HannSymmetric ? "hann_symmetric" : "hann";
}

// printf's "%.10g" (the standard defines to_chars with a precision so), without the
// locale and format-string work: 254 k fragment rows of 18 numbers on a crushed block.
std::string fmt(double v) {
  char buf[40];
  const auto r = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::general, 10);
  return std::string(buf, r.ptr);
}

std::string step_suffix(const OutputInfo& o) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "_%06lld", o.step);
  return buf;
}

// Whether two labelings split the particles into the same pieces (labels may differ): a
// bijection maps one onto the other. Returns the number of particles that break it.
size_t partition_mismatches(std::span<const int32_t> a, std::span<const int32_t> b) {
  std::map<int32_t, int32_t> ab, ba;
  size_t bad = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    const auto [x, fresh_a] = ab.try_emplace(a[i], b[i]);
    const auto [y, fresh_b] = ba.try_emplace(b[i], a[i]);
    bad += x->second != b[i] || y->second != a[i];
  }
  return bad;
}

std::string shell_quote(const std::string& s) {
  std::string out = "'";
  for (char c : s) {
    if (c == '\'') out += "'\\''";
    else out += c;
  }
  return out + "'";
}

struct StepRecord {
  OutputInfo info;
  bool has_cracks = false, has_fragments = false;
  CrackResult cracks;
  int32_t fragment_count = 0;
};

class Runner {
public:
  explicit Runner(const PostOptions& o) : opt_(o) {}
  ~Runner() { stop_plots(); }
  Runner(const Runner&) = delete;
  Runner& operator=(const Runner&) = delete;

  PostSummary run() {
    auto last = std::chrono::steady_clock::now();
    auto phase = [&](const char* name) {
      const auto now = std::chrono::steady_clock::now();
      summary_.phases.emplace_back(name, std::chrono::duration<double>(now - last).count());
      last = now;
    };
    threads_ = opt_.threads > 0 ? opt_.threads : omp_get_max_threads();
    run_ = open_run(opt_.run_dir, opt_.particles_file);
    phase("read run");
    if (run_.outputs.empty() && (opt_.cracks || opt_.fragments))
      throw InputError(run_.results_path.string(), "/@output_count", "0 outputs", "at least one output group");
    summary_.post_dir = opt_.run_dir / "post";
    // A run folder this user cannot write (a colleague's results): bad input, said before the work.
    if (const std::string why = folder_write_problem(summary_.post_dir); !why.empty())
      throw InputError(summary_.post_dir.string(), "", "not writable (" + why + ")",
                       "a run folder this user can write (breccia-post writes RUN_DIR/post)");
    select_outputs();
    // history.csv first: the charts that read it alone are drawn beside everything else.
    load_history();
    if (opt_.plots && energy_balance_applies() && history_->rows() > 0)
      plot("plot_energy.py", "--history " + shell_quote((energy_history_.empty() ? history_->path : energy_history_).string()),
           "energy.png");
    if (opt_.plots && opt_.energy && history_ && history_->find("gas_pressure_Pa"))  // a gas load (solver gas.hpp)
      plot("plot_gas.py", "--history " + shell_quote(history_->path.string()), "gas.png");
    phase("history.csv");
    const bool need_faces = opt_.cracks || opt_.energy;
    if (!run_.outputs.empty() && (need_faces || opt_.fragments)) {
      precracks_ = RemovedBonds(run_.precrack_bonds, run_.size());
      // Lattice faces need only the partners j > i at one spacing: the half list serves.
      if (need_faces) {
        faces_ = candidate_faces(run_.particles, run_.bonds);
        // Each face's bond, looked up once: an output then reads one bit per face.
        face_bond_.resize(faces_.size());
        for (size_t f = 0; f < faces_.size(); ++f)
          face_bond_[f] = bond_index(run_.bonds, faces_.particle_a[f], faces_.particle_b[f]);
      }
    }
    phase("bond faces");
    // The crack history (every output's cracks) and the analysis of the selected outputs read
    // the same run and write different files: with a second thread they run side by side (the
    // history on threads_ - 1 threads), each read of results.h5 under its mutex.
    const bool history = !run_.outputs.empty() && need_faces;
    const fs::path history_path = history ? out("crack_history.csv") : fs::path();
    const bool beside = history && threads_ > 1;
    std::future<std::string> history_csv;
    if (beside) history_csv = std::async(std::launch::async, [this] { return crack_history(threads_ - 1); });
    if (history && !beside) {
      write_text_file(history_path, crack_history(1));
      phase("crack history");
    }
    for (size_t k = 0; k < analysed_.size(); ++k) {
      if (analysed_.size() > 1 && opt_.progress)
        std::fprintf(stderr, "[post] output %zu/%zu (step %lld)\n", k + 1, analysed_.size(), run_.outputs[analysed_[k]].step);
      analyse_output(analysed_[k], k + 1 == analysed_.size());
    }
    if (opt_.all_steps) write_collections();
    phase(beside ? "outputs (cracks, fragments, fields; the crack history beside them)" : "outputs (cracks, fragments, fields)");
    if (beside) {
      write_text_file(history_path, history_csv.get());
      phase("crack history (the rest, after the outputs)");
    }
    if (energy_balance_applies()) energy();
    if (opt_.probes && history_) probes();
    phase("energy, probes");
    finish_plots();
    phase("charts (the rest, after the other work)");
    write_json();
    phase("summary");
    return summary_;
  }

private:
  void select_outputs() {
    if (run_.outputs.empty()) return;
    if (opt_.all_steps) {
      for (size_t k = 0; k < run_.outputs.size(); ++k) analysed_.push_back(k);
    } else if (opt_.step) {
      analysed_.push_back(run_.output_index_of_step(*opt_.step));
    } else {
      analysed_.push_back(run_.outputs.size() - 1);
    }
  }

  fs::path out(const std::string& name) {
    summary_.written.push_back(name);
    return summary_.post_dir / name;
  }

  CrackInputs crack_inputs(const BondSet& broken, std::span<const double> damage) const {
    return CrackInputs{&broken, &precracks_, damage, run_.material_id, run_.fracture_energy_J_m2, {}, 0};
  }

  // crack_history.csv's text: one row per output, the outputs on `threads` threads (rows in
  // output order whatever the count).
  std::string crack_history(int threads) {
    const size_t outputs = run_.outputs.size();
    Progress progress("crack history", static_cast<long long>(outputs));
    std::mutex progress_mutex;
    long long done = 0;
    std::vector<std::string> rows(outputs);
    // No fracture energy (MPS): the G0 x area cells stay empty rather than 0.
    const bool g0 = !run_.fracture_energy_J_m2.empty();
    // An exception may not leave an OpenMP region: the first is kept and rethrown after it.
    std::exception_ptr error;
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
    for (size_t k = 0; k < outputs; ++k) {
      try {
        const OutputFrame fr = read_output_cracks_only(run_, k);
        const BondBits broken(run_.bonds, fr.broken, face_bond_);
        const CrackResult c = find_cracks(faces_, crack_inputs(broken, fr.damage), opt_.crack_criterion, opt_.damage_threshold);
        std::ostringstream row;
        row << k << ',' << fr.info.step << ',' << fmt(fr.info.time_s) << ',' << fmt(c.area_m2) << ','
            << fmt(c.fracture_area_m2) << ',' << fmt(c.precrack_area_m2) << ',' << fmt(c.length_m) << ','
            << c.crack_count << ',' << c.face_count << ',' << fr.broken_count << ',' << (g0 ? fmt(c.G0_area_J) : "") << ','
            << fmt(c.smoothed_area_m2) << ',' << fmt(c.smoothed_fracture_area_m2) << ','
            << (g0 ? fmt(c.G0_smoothed_area_J) : "") << '\n';
        rows[k] = row.str();
        const std::lock_guard<std::mutex> lock(progress_mutex);
        if (opt_.progress) progress.update(++done);
      } catch (...) {
        const std::lock_guard<std::mutex> lock(progress_mutex);
        if (!error) error = std::current_exception();
      }
    }
    if (error) std::rethrow_exception(error);
    std::string csv =
        "output,step,time_s,crack_area_m2,fracture_area_m2,precrack_area_m2,crack_length_m,crack_count,"
        "crack_faces,broken_bonds,G0_times_fracture_area_J,smoothed_crack_area_m2,smoothed_fracture_area_m2,"
        "G0_times_smoothed_fracture_area_J\n";
    for (const auto& row : rows) csv += row;
    return csv;
  }

  void analyse_output(size_t index, bool last) {
    const OutputFrame fr = read_output(run_, index);
    const std::string sfx = opt_.all_steps ? step_suffix(fr.info) : "";
    const BondBits broken(run_.bonds, fr.broken, face_bond_);
    StepRecord rec;
    rec.info = fr.info;
    const bool has_mesh = run_.particles.nodes_per_cell > 0;
    int32_t count = 0;
    std::vector<int32_t> comp;  // fragments: components of the intact bond graph
    if (opt_.cracks || opt_.energy || opt_.fragments) comp = intact_components(run_.bonds, run_.within_horizon, fr.broken, precracks_, &count);
    if (opt_.cracks || opt_.energy) {
      CrackInputs in = crack_inputs(broken, fr.damage);
      in.fragment_of = comp;  // through-crack (separating) measures
      // Debris: pieces smaller than one horizon family, too small to have a bulk of their own
      // (mean family size: each within-horizon bond counted from both ends).
      in.debris_particles = run_.size() == 0 ? 0
                                : 1 + static_cast<int64_t>(2 * run_.within_horizon_count) / static_cast<int64_t>(run_.size());
      rec.cracks = find_cracks(faces_, in, opt_.crack_criterion, opt_.damage_threshold);
      rec.has_cracks = true;
    }
    if (opt_.cracks) {
      write_vtp(out("cracks" + sfx + ".vtp"), crack_mesh(faces_, rec.cracks));
      if (has_mesh) {
        Mesh mesh = source_mesh(run_.particles);
        mesh.point_data.push_back({"damage", 1, cell_to_node_average(run_.particles, fr.damage), false});
        write_contour_vtp(out("damage_iso" + sfx + ".vtp"), mesh, "damage", opt_.damage_threshold);
      } else if (last) {
        notes_.push_back("damage_iso.vtp not written: lattice model without a source mesh");
      }
    }
    if (opt_.fragments) {
      FragmentInputs in{run_.dimension, run_.thickness_m, run_.position_m, fr.displacement_m,
                        fr.velocity_m_s, run_.volume_m3, run_.density_kg_m3};
      const FragmentResult frag = measure_fragments(in, comp, count, opt_.min_fragment_particles);
      rec.has_fragments = true;
      rec.fragment_count = static_cast<int32_t>(frag.fragments.size());
      if (last) compare_solver_fragments(fr.info, comp);
      // The last output's size distribution first, so that its chart is drawn while the
      // meshes below are written.
      if (last) {
        fragments_ = frag;
        distribution();
      }
      write_fragments_csv(out("fragments" + sfx + ".csv"), frag);
      write_fragments_vtu(out("fragments" + sfx + ".vtu"), frag, fr);
      Mesh deformed = deformed_mesh(run_.particles, fr.displacement_m, comp);
      deformed.cell_data.push_back({"fragment_id", 1, std::vector<double>(frag.fragment_id.begin(), frag.fragment_id.end()), true});
      deformed.cell_data.push_back({"damage", 1, fr.damage, false});
      write_vtu(out("deformed" + sfx + ".vtu"), deformed);
    }
    if (opt_.all_steps) {
      if (opt_.cracks) pvd_["cracks"].emplace_back(fr.info.time_s, "cracks" + sfx + ".vtp");
      if (opt_.cracks && has_mesh) pvd_["damage_iso"].emplace_back(fr.info.time_s, "damage_iso" + sfx + ".vtp");
      if (opt_.fragments) {
        pvd_["fragments"].emplace_back(fr.info.time_s, "fragments" + sfx + ".vtu");
        pvd_["deformed"].emplace_back(fr.info.time_s, "deformed" + sfx + ".vtu");
      }
    }
    records_.push_back(std::move(rec));
  }

  // An MPS run with fracture writes its own pieces (/output/NNNNNN/fragment, a union-find over
  // the same intact bonds): post's components must be the same partition.
  void compare_solver_fragments(const OutputInfo& info, const std::vector<int32_t>& comp) {
    std::vector<int32_t> labels;
    {
      const std::lock_guard<std::mutex> lock(results_file_mutex());  // the crack history may be reading
      const h5::File f(run_.results_path.string(), h5::File::Mode::Read);
      if (!f.exists(info.group + "/fragment")) return;
      labels = f.read_int32(info.group + "/fragment");
    }
    if (labels.size() != comp.size())
      throw InputError(run_.results_path.string(), info.group + "/fragment", "size " + std::to_string(labels.size()),
                       "N = " + std::to_string(comp.size()));
    solver_fragment_mismatches_ = static_cast<long long>(partition_mismatches(comp, labels));
    if (solver_fragment_mismatches_ > 0)
      notes_.push_back("the solver's fragment labels differ from post's components at " +
                       std::to_string(solver_fragment_mismatches_) + " particles");
  }

  void write_collections() {
    for (const auto& [name, entries] : pvd_) write_pvd(out(name + ".pvd"), entries);
  }

  void write_fragments_csv(const fs::path& path, const FragmentResult& fr) {
    std::ostringstream csv;
    csv << "fragment_id,particle_count,volume_m3,mass_kg,centroid_x_m,centroid_y_m,centroid_z_m,"
           "reference_centroid_x_m,reference_centroid_y_m,reference_centroid_z_m,velocity_x_m_s,velocity_y_m_s,"
           "velocity_z_m_s,equivalent_diameter_m,box_long_m,box_mid_m,box_short_m,sieve_size_m\n";
    for (size_t k = 0; k < fr.fragments.size(); ++k) {
      const Fragment& f = fr.fragments[k];
      csv << k << ',' << f.particle_count << ',' << fmt(f.volume_m3) << ',' << fmt(f.mass_kg);
      for (double v : f.centroid_m) csv << ',' << fmt(v);
      for (double v : f.centroid_reference_m) csv << ',' << fmt(v);
      for (double v : f.velocity_m_s) csv << ',' << fmt(v);
      csv << ',' << fmt(f.equivalent_diameter_m);
      for (double v : f.box_m) csv << ',' << fmt(v);
      csv << ',' << fmt(f.sieve_size_m) << '\n';
    }
    write_text_file(path, csv.str());
  }

  void write_fragments_vtu(const fs::path& path, const FragmentResult& fr, const OutputFrame& frame) {
    Mesh mesh = source_mesh(run_.particles);
    std::vector<Field>& data = run_.particles.nodes_per_cell > 0 ? mesh.cell_data : mesh.point_data;
    data.push_back({"fragment_id", 1, std::vector<double>(fr.fragment_id.begin(), fr.fragment_id.end()), true});
    data.push_back({"component", 1, std::vector<double>(fr.component.begin(), fr.component.end()), true});
    data.push_back({"damage", 1, frame.damage, false});
    data.push_back({"displacement", 3, frame.displacement_m, false});
    data.push_back({"velocity", 3, frame.velocity_m_s, false});
    data.push_back({"material_id", 1, std::vector<double>(run_.material_id.begin(), run_.material_id.end()), true});
    write_vtu(path, mesh);
  }

  void distribution() {
    std::vector<double> size, mass;
    for (const Fragment& f : fragments_.fragments) {
      size.push_back(opt_.size_by_diameter ? f.equivalent_diameter_m : f.sieve_size_m);
      mass.push_back(f.mass_kg);
    }
    dist_ = size_distribution(size, mass);
    std::ostringstream csv;
    csv << "size_m,passing,rosin_rammler,swebrec\n";
    for (size_t k = 0; k < dist_.size_m.size(); ++k) {
      const double x = dist_.size_m[k];
      csv << fmt(x) << ',' << fmt(dist_.passing[k]) << ','
          << (dist_.fitted ? fmt(dist_.rosin_rammler.passing(x)) : "") << ','
          << (dist_.fitted ? fmt(dist_.swebrec.passing(x)) : "") << '\n';
    }
    write_text_file(out("size_distribution.csv"), csv.str());
    if (!opt_.plots) return;
    if (!dist_.fitted) {
      notes_.push_back("fragment_sizes.png not drawn: fewer than 3 distinct fragment sizes");
      return;
    }
    std::string args = "--data " + shell_quote((summary_.post_dir / "size_distribution.csv").string()) +
                       " --rosin-rammler " + fmt(dist_.rosin_rammler.xc_m) + " " + fmt(dist_.rosin_rammler.n) +
                       " --swebrec " + fmt(dist_.swebrec.xmax_m) + " " + fmt(dist_.swebrec.x50_m) + " " +
                       fmt(dist_.swebrec.b) + " --fragments " + std::to_string(dist_.fragment_count) + " --size-label " +
                       shell_quote(opt_.size_by_diameter ? "equivalent diameter" : "sieve size");
    plot("plot_fragment_sizes.py", args, "fragment_sizes.png");
  }

  // A chart: its script run by the Python interpreter. With two or more threads the charts are
  // drawn one after another by a thread of their own (plots_worker_), so that post goes on
  // meanwhile; finish_plots collects them in the order asked, the same list of files with any
  // thread count.
  void plot(const std::string& script, const std::string& args, const std::string& png) {
    const fs::path dir = opt_.scripts_dir.empty() ? default_scripts_dir() : opt_.scripts_dir;
    std::string cmd = shell_quote(opt_.python) + " " + shell_quote((dir / script).string()) + " " + args + " --out " +
                      shell_quote((summary_.post_dir / png).string()) + " >> " + shell_quote(plots_log().string()) +
                      " 2>&1";
    if (threads_ < 2) {
      const int rc = std::system(cmd.c_str());
      plots_.push_back({script, png, std::move(cmd), rc});
      return;
    }
    {
      const std::lock_guard<std::mutex> lock(plots_mutex_);
      plots_.push_back({script, png, std::move(cmd), -1});  // a deque: the worker's element stays put
    }
    plots_ready_.notify_one();
    if (!plots_worker_.joinable()) plots_worker_ = std::thread([this] { draw_plots(); });
  }

  // The chart thread: each queued command in order, until finish_plots closes the queue.
  void draw_plots() {
    std::unique_lock<std::mutex> lock(plots_mutex_);
    for (;;) {
      plots_ready_.wait(lock, [this] { return plots_drawn_ < plots_.size() || plots_closed_; });
      if (plots_drawn_ == plots_.size()) return;  // closed, nothing left
      const size_t k = plots_drawn_;
      const std::string cmd = plots_[k].cmd;
      lock.unlock();
      const int rc = std::system(cmd.c_str());
      lock.lock();
      plots_[k].rc = rc;
      ++plots_drawn_;
    }
  }

  // Waits for the chart thread to draw what was asked and stop (also on the way out of an
  // error: a joinable thread may not be destroyed).
  void stop_plots() {
    {
      const std::lock_guard<std::mutex> lock(plots_mutex_);
      plots_closed_ = true;
    }
    plots_ready_.notify_one();
    if (plots_worker_.joinable()) plots_worker_.join();
  }

  void finish_plots() {
    stop_plots();
    for (const auto& p : plots_) {
      if (p.rc == 0 && fs::exists(summary_.post_dir / p.png)) {
        summary_.written.push_back(p.png);
        continue;
      }
      const std::string msg = p.png + ": " + p.script + " failed (exit " + std::to_string(p.rc) + "), see " + plots_log().string();
      summary_.plot_failures.push_back(msg);
      std::fprintf(stderr, "warning: %s; the numerical results are unaffected\n", msg.c_str());
    }
  }

  // Every chart script appends its output to this one log.
  fs::path plots_log() const { return summary_.post_dir / "plots.log"; }

  // The energy balance (and its chart) apply: asked for, history.csv read, energy columns in it.
  bool energy_balance_applies() const { return opt_.energy && history_ && energy_available_; }

  void load_history() {
    const fs::path p = opt_.run_dir / "history.csv";
    const bool wanted = opt_.energy || opt_.probes;
    if (!wanted) return;
    if (!fs::exists(p)) {
      if (opt_.history_required)
        throw InputError(p.string(), "", "file does not exist", "history.csv written by breccia-solve (needed for --energy/--spectrum)");
      notes_.push_back("history.csv absent: no energy balance, probe histories or spectra");
      return;
    }
    history_ = read_history(p);
    if (run_.model == "mps") map_mps(p);
  }

  // An MPS history in post's names (mps_history.hpp); the mapped balance terms also go to
  // post/energy_history.csv, which the energy chart reads.
  void map_mps(const fs::path& p) {
    MpsHistoryMapping m = map_mps_history(*history_);
    history_ = std::move(m.history);
    mps_terms_ = std::move(m.terms);
    if (opt_.energy)  // every note of the mapping is about the energy balance
      for (auto& note : m.notes) notes_.push_back(std::move(note));
    energy_available_ = m.energy;
    if (!m.energy) {
      if (opt_.energy && opt_.history_required)
        throw InputError(p.string(), "header", "no kinetic_energy_J column",
                         "the energy columns of an MPS run (output.energy: true in the case) for --energy");
      return;
    }
    const History& h = *history_;
    std::ostringstream csv;
    csv << "time_s,kinetic_J,strain_J,external_work_J,dissipated_J,total_J\n";
    for (size_t r = 0; r < h.rows(); ++r) {
      const double k = h.column("kinetic_J")[r], u = h.column("strain_J")[r], w = h.column("external_work_J")[r],
                   d = h.column("dissipated_J")[r];
      csv << fmt(h.column("time_s")[r]) << ',' << fmt(k) << ',' << fmt(u) << ',' << fmt(w) << ',' << fmt(d) << ','
          << fmt(k + u + d - w) << '\n';
    }
    energy_history_ = out("energy_history.csv");
    write_text_file(energy_history_, csv.str());
  }

  void energy() {
    const History& h = *history_;
    for (const char* c : {"time_s", "kinetic_J", "strain_J", "external_work_J", "dissipated_J"}) h.column(c);
    energy_done_ = true;
    const auto& dissipated = h.column("dissipated_J");
    size_t row = h.rows() ? h.rows() - 1 : 0;
    const StepRecord* rec = records_.empty() ? nullptr : &records_.back();
    if (rec && h.find("step")) {
      const auto& steps = h.column("step");
      for (size_t k = 0; k < h.rows(); ++k)
        if (steps[k] <= static_cast<double>(rec->info.step)) row = k;
    } else if (rec) {  // an MPS history has times only: the last row at or before the output
      const auto& t = h.column("time_s");
      for (size_t k = 0; k < h.rows(); ++k)
        if (t[k] <= rec->info.time_s * (1.0 + 1e-12)) row = k;
    }
    if (h.rows() == 0) return;
    energy_row_ = row;
    energy_dissipated_J_ = dissipated[row];
    // No fracture energy in the run (MPS: a strength criterion): no G0 x area to compare with.
    const bool g0 = rec && rec->has_cracks && !run_.fracture_energy_J_m2.empty();
    energy_G0_area_J_ = g0 ? rec->cracks.G0_smoothed_area_J : NAN;
    energy_G0_face_area_J_ = g0 ? rec->cracks.G0_area_J : NAN;
    energy_G0_separating_area_J_ = g0 && rec->cracks.has_separating ? rec->cracks.G0_smoothed_separating_area_J : NAN;
    // What the run holds at a row, and the energy it started with (the first row: an initial
    // velocity or displacement field gives K0 or U0 > 0 with no work done).
    const auto& work = h.column("external_work_J");
    const auto held = [&](size_t k) { return h.column("kinetic_J")[k] + h.column("strain_J")[k] + dissipated[k]; };
    const double supplied = work[row] + (held(0) - work[0]), stored = held(row);
    energy_imbalance_ = (supplied - stored) / std::max({std::abs(supplied), std::abs(stored), 1e-300});
    // (Its chart was asked for when history.csv was read: run.)
  }

  // Uniform samples for the FFT; linear resampling when the history is not uniform.
  std::vector<double> uniform(const std::vector<double>& t, const std::vector<double>& v, double& dt, bool& resampled) {
    const size_t n = t.size();
    dt = (t.back() - t.front()) / static_cast<double>(n - 1);
    resampled = false;
    // Uniform within 1e-6 of a step, plus the rounding of times history.csv prints to 10
    // significant digits (5e-10 of t: past 2,000 rows that exceeded 1e-6 dt alone, and every
    // long uniform record was flagged as resampled).
    for (size_t k = 0; k < n; ++k)
      if (std::abs(t[k] - t.front() - k * dt) > 1e-6 * dt + 1e-9 * std::abs(t[k])) resampled = true;
    if (!resampled) return v;
    std::vector<double> out(n);
    size_t j = 0;
    for (size_t k = 0; k < n; ++k) {
      const double tk = t.front() + k * dt;
      while (j + 2 < n && t[j + 1] < tk) ++j;
      const double s = t[j + 1] > t[j] ? (tk - t[j]) / (t[j + 1] - t[j]) : 0.0;
      out[k] = v[j] + std::clamp(s, 0.0, 1.0) * (v[j + 1] - v[j]);
    }
    return out;
  }

  void probes() {
    const History& h = *history_;
    const std::vector<std::string> names = h.probe_names();
    std::vector<std::string> spectra = opt_.spectrum_probes;
    for (const auto& s : spectra) {
      if (std::find(names.begin(), names.end(), s) != names.end() || h.find("probe_" + s)) continue;
      std::string have;
      for (const auto& n : names) have += (have.empty() ? "" : ", ") + n;
      throw InputError(h.path.string(), "--spectrum " + s, "no column probe_" + s + "_<component> or probe_" + s,
                       "one of the probes in the header: " + (have.empty() ? std::string("(none)") : have));
    }
    if (spectra.empty() && opt_.spectrum_all) spectra = names;
    const auto& t = h.column("time_s");
    for (const auto& name : names) {
      const auto cols = h.probe_columns(name);
      std::ostringstream csv;
      csv << "time_s";
      for (const auto& c : cols) csv << ',' << c.substr(7 + name.size());
      csv << '\n';
      for (size_t r = 0; r < h.rows(); ++r) {
        csv << fmt(t[r]);
        for (const auto& c : cols) csv << ',' << fmt(h.column(c)[r]);
        csv << '\n';
      }
      const std::string file = "probe_" + name + ".csv";
      write_text_file(out(file), csv.str());
      if (opt_.plots)
        plot("plot_series.py", "--kind probe --data " + shell_quote((summary_.post_dir / file).string()) +
                                   " --title " + shell_quote("probe " + name), "probe_" + name + ".png");
    }
    for (const auto& s : spectra) spectrum(s, t);
  }

  void spectrum(const std::string& probe, const std::vector<double>& t) {
    const History& h = *history_;
    std::vector<std::string> cols = h.probe_columns(probe);
    if (cols.empty()) cols = {"probe_" + probe};
    // A gate outside the record is bad input however short the record (checked first).
    if (opt_.gate_s && !t.empty() && !(opt_.gate_s->first >= t.front() && opt_.gate_s->second <= t.back()))
      throw InputError("command line", "--gate", fmt(opt_.gate_s->first) + "," + fmt(opt_.gate_s->second) + " s",
                       "a gate inside the record of " + h.path.string() + ", [" + fmt(t.front()) + ", " + fmt(t.back()) + "] s");
    if (h.rows() < 4) {
      notes_.push_back("spectrum of " + probe + " skipped: fewer than 4 samples");
      return;
    }
    // --gate: the rows with t0 <= t <= t1 (the record's own sample times, before any resampling).
    GateRows rows{0, t.size()};
    if (opt_.gate_s) {
      const auto [t0, t1] = *opt_.gate_s;
      rows = gate_rows(t, t0, t1);
      if (rows.last - rows.first < 4)
        throw InputError("command line", "--gate", std::to_string(rows.last - rows.first) + " samples in " + fmt(t0) + "," + fmt(t1) + " s",
                         "a gate holding at least 4 samples of " + h.path.string());
    }
    const std::vector<double> tg(t.begin() + rows.first, t.begin() + rows.last);
    SpectrumOptions so;
    so.window = spectrum_window(opt_);
    so.reference_Hz = opt_.frequency_Hz;
    so.resolution_Hz = opt_.resolution_Hz;
    so.band_Hz = opt_.band_Hz;
    std::vector<std::pair<std::string, Spectrum>> comps;
    bool resampled = false;
    for (const auto& c : cols) {
      double dt = 0;
      bool rs = false;
      const std::vector<double> vg(h.column(c).begin() + rows.first, h.column(c).begin() + rows.last);
      const std::vector<double> v = uniform(tg, vg, dt, rs);
      if (!(dt > 0))
        throw InputError(h.path.string(), "time_s", "no increase over " + std::to_string(tg.size()) + " rows",
                         "increasing sample times for the spectrum of probe " + probe);
      resampled = resampled || rs;
      for (size_t k = 0; k < vg.size(); ++k)
        if (!std::isfinite(vg[k]))
          throw InputError(h.path.string(), c, std::to_string(vg[k]) + " at t = " + fmt(tg[k]) + " s",
                           "finite values for the spectrum of probe " + probe);
      if (opt_.frequency_Hz && *opt_.frequency_Hz > 0.5 / dt)
        throw InputError("command line", "--frequency", fmt(*opt_.frequency_Hz) + " Hz",
                         "a frequency below the Nyquist frequency of " + h.path.string() + "'s samples, " + fmt(0.5 / dt) + " Hz");
      const std::string comp = c.size() > 7 + probe.size() ? c.substr(7 + probe.size()) : c;
      try {
        comps.emplace_back(comp, amplitude_spectrum(v, dt, so));
      } catch (const std::invalid_argument& e) {  // samples and dt are checked above: a band holding no bin
        if (!opt_.band_Hz) throw;
        throw InputError("command line", "--band", fmt(*opt_.band_Hz) + " Hz", std::string("a band wider than the bins (") + e.what() + ")");
      }
    }
    std::ostringstream csv;
    csv << "frequency_Hz";
    for (const auto& [c, s] : comps) csv << ",amplitude_" << c << ",normalised_" << c;
    csv << '\n';
    for (size_t k = 0; k < comps.front().second.frequency_Hz.size(); ++k) {
      csv << fmt(comps.front().second.frequency_Hz[k]);
      for (const auto& [c, s] : comps) csv << ',' << fmt(s.amplitude[k]) << ',' << fmt(s.normalised[k]);
      csv << '\n';
    }
    const std::string file = "spectrum_" + probe + ".csv";
    write_text_file(out(file), csv.str());
    spectra_.push_back({probe, comps, resampled});
    if (opt_.plots)
      plot("plot_series.py", "--kind spectrum --data " + shell_quote((summary_.post_dir / file).string()) +
                                 " --title " + shell_quote("probe " + probe + (opt_.hann ? ", Hann window" : "") +
                                                           (opt_.gate_s ? ", gate " + fmt(opt_.gate_s->first) + "-" + fmt(opt_.gate_s->second) + " s" : "")),
           "spectrum_" + probe + ".png");
  }

  // Doubles go through json_number (null when not finite: a ratio without a G0 area).
  void write_cracks_json(Json& j, const CrackResult& c) {
    j["crack_area_m2"] = json_number(c.area_m2);
    j["fracture_area_m2"] = json_number(c.fracture_area_m2);
    j["precrack_area_m2"] = json_number(c.precrack_area_m2);
    if (run_.dimension == 2) {
      j["crack_length_m"] = json_number(c.length_m);
      j["fracture_length_m"] = json_number(c.fracture_length_m);
    }
    j["smoothed_crack_area_m2"] = json_number(c.smoothed_area_m2);
    j["smoothed_fracture_area_m2"] = json_number(c.smoothed_fracture_area_m2);
    if (run_.dimension == 2) j["smoothed_crack_length_m"] = json_number(c.smoothed_length_m);
    j["smoothing_radius_m"] = json_number(c.smoothing_radius_m);
    // Without a fracture energy (MPS) the G0 x area terms would be zeros standing for "unknown".
    const bool g0 = !run_.fracture_energy_J_m2.empty();
    j["crack_count"] = c.crack_count;
    j["crack_faces"] = c.face_count;
    if (g0) {
      j["G0_times_fracture_area_J"] = json_number(c.G0_area_J);
      j["G0_times_smoothed_fracture_area_J"] = json_number(c.G0_smoothed_area_J);
    }
    if (c.has_separating) {
      j["separating_faces"] = c.separating_face_count;
      j["separating_fracture_area_m2"] = json_number(c.separating_fracture_area_m2);
      j["smoothed_separating_fracture_area_m2"] = json_number(c.smoothed_separating_fracture_area_m2);
      if (g0) j["G0_times_smoothed_separating_area_J"] = json_number(c.G0_smoothed_separating_area_J);
    }
  }

  void write_json() {
    Json j;
    j["format"] = "breccia-post";
    j["format_version"] = 1;
    j["results_file"] = run_.results_path.string();
    j["particles_file"] = run_.particles_path.string();
    j["model"] = run_.model;
    j["dimension"] = run_.dimension;
    j["particles"] = run_.size();
    j["crack_criterion"] = opt_.crack_criterion == CrackCriterion::Bond ? "bond" : "damage";
    j["damage_threshold"] = json_number(opt_.damage_threshold);
    if (!records_.empty()) {
      const StepRecord& r = records_.back();
      j["step"] = r.info.step;
      j["time_s"] = json_number(r.info.time_s);
      if (r.has_cracks) {
        Json cracks = Json::object();
        write_cracks_json(cracks, r.cracks);
        j["cracks"] = std::move(cracks);
      }
    }
    if (!fragments_.component.empty()) {
      Json f;
      f["fragment_count"] = fragments_.fragments.size();
      f["component_count"] = fragments_.component_count;
      f["min_fragment_particles"] = opt_.min_fragment_particles;
      f["filtered_out_count"] = fragments_.filtered_count;
      f["filtered_out_mass_kg"] = json_number(fragments_.filtered_mass_kg);
      // MPS with fracture: particles where the solver's own `fragment` labels split differently (0: same pieces).
      if (solver_fragment_mismatches_ >= 0) f["solver_fragment_mismatches"] = solver_fragment_mismatches_;
      if (!fragments_.fragments.empty()) {
        const Fragment& big = fragments_.fragments.front();
        f["largest_mass_kg"] = json_number(big.mass_kg);
        f["largest_volume_m3"] = json_number(big.volume_m3);
      }
      j["fragments"] = std::move(f);
      Json d;
      d["size_measure"] = opt_.size_by_diameter ? "equivalent_diameter" : "sieve_size";
      d["fragment_count"] = dist_.fragment_count;
      d["x50_m"] = json_number(dist_.x50_m);
      d["x80_m"] = json_number(dist_.x80_m);
      d["fitted"] = dist_.fitted;
      if (dist_.fitted) {
        const auto& rr = dist_.rosin_rammler;
        const auto& sw = dist_.swebrec;
        d["rosin_rammler"] = Json{{"xc_m", json_number(rr.xc_m)}, {"n", json_number(rr.n)},
                                  {"x50_m", json_number(rr.x50_m)}, {"x80_m", json_number(rr.x80_m)},
                                  {"r_squared", json_number(rr.r2)}};
        d["swebrec"] = Json{{"xmax_m", json_number(sw.xmax_m)}, {"x50_m", json_number(sw.x50_m)},
                            {"b", json_number(sw.b)}, {"x80_m", json_number(sw.x80_m)},
                            {"r_squared", json_number(sw.r2)}};
      }
      j["size_distribution"] = std::move(d);
    }
    if (energy_done_) {
      auto ratio = [&](double g0_area) { return json_number(g0_area > 0 ? energy_dissipated_J_ / g0_area : NAN); };
      Json e;
      e["history_row"] = energy_row_;
      e["dissipated_J"] = json_number(energy_dissipated_J_);
      e["G0_times_crack_area_J"] = json_number(energy_G0_area_J_);
      e["ratio"] = ratio(energy_G0_area_J_);
      e["G0_times_face_area_J"] = json_number(energy_G0_face_area_J_);
      e["ratio_face_area"] = ratio(energy_G0_face_area_J_);
      e["G0_times_separating_area_J"] = json_number(energy_G0_separating_area_J_);
      e["ratio_separating"] = ratio(energy_G0_separating_area_J_);
      e["relative_imbalance"] = json_number(energy_imbalance_);
      if (!mps_terms_.empty()) {
        Json terms;  // what each balance term is made of in an MPS run
        for (const auto& [term, source] : mps_terms_) terms[term] = source;
        e["mps_terms"] = std::move(terms);
      }
      j["energy"] = std::move(e);
    }
    if (!spectra_.empty()) {
      Json spectra = Json::array();
      for (const auto& sp : spectra_) {
        for (const auto& [comp, s] : sp.components) {
          Json o;
          o["probe"] = sp.probe;
          o["component"] = comp;
          o["window"] = window_name(spectrum_window(opt_));
          if (opt_.gate_s) o["gate_s"] = Json::array({json_number(opt_.gate_s->first), json_number(opt_.gate_s->second)});
          o["samples"] = static_cast<long long>(s.samples);
          o["transform_length"] = static_cast<long long>(s.transform_length);
          if (opt_.band_Hz) o["band_Hz"] = json_number(*opt_.band_Hz);
          o["resampled"] = sp.resampled;
          o["reference_frequency_Hz"] = json_number(s.reference_frequency_Hz);
          o["reference_amplitude"] = json_number(s.reference_amplitude);
          Json harmonics = Json::array();
          for (const auto& hm : s.harmonics)
            harmonics.push_back(Json{{"order", hm.order}, {"frequency_Hz", json_number(hm.frequency_Hz)},
                                     {"amplitude", json_number(hm.amplitude)}, {"ratio", json_number(hm.ratio)}});
          o["harmonics"] = std::move(harmonics);
          spectra.push_back(std::move(o));
        }
      }
      j["spectra"] = std::move(spectra);
    }
    if (records_.size() > 1) {
      Json outputs = Json::array();
      for (const auto& r : records_) {
        Json o;
        o["step"] = r.info.step;
        o["time_s"] = json_number(r.info.time_s);
        if (r.has_cracks) write_cracks_json(o, r.cracks);
        if (r.has_fragments) o["fragment_count"] = r.fragment_count;
        outputs.push_back(std::move(o));
      }
      j["outputs"] = std::move(outputs);
    }
    Json files = summary_.written;
    files.push_back("post.json");
    j["files"] = std::move(files);
    j["plot_failures"] = summary_.plot_failures;
    j["notes"] = notes_;
    write_json_file(summary_.post_dir / "post.json", j);
    summary_.written.push_back("post.json");
  }

  struct SpectrumRecord {
    std::string probe;
    std::vector<std::pair<std::string, Spectrum>> components;
    bool resampled = false;
  };

  const PostOptions& opt_;
  int threads_ = 1;  // opt_.threads, or OpenMP's count
  PostSummary summary_;
  RunData run_;
  // Charts asked for (plot), in order, and the thread that draws them (draw_plots): it has
  // drawn the first plots_drawn_; plots_mutex_ guards the queue, rc and the counters.
  struct PendingPlot {
    std::string script, png;
    std::string cmd;
    int rc = -1;  // the interpreter's exit status
  };
  std::deque<PendingPlot> plots_;
  std::mutex plots_mutex_;
  std::condition_variable plots_ready_;
  size_t plots_drawn_ = 0;
  bool plots_closed_ = false;
  std::thread plots_worker_;
  std::vector<size_t> analysed_;
  RemovedBonds precracks_;
  std::vector<int64_t> face_bond_;  // per candidate face: its bond in run_.bonds, -1 if none
  CandidateFaces faces_;
  std::vector<StepRecord> records_;
  FragmentResult fragments_;
  SizeDistribution dist_;
  std::optional<History> history_;
  std::map<std::string, std::vector<std::pair<double, std::string>>> pvd_;
  std::vector<std::string> notes_;
  std::vector<SpectrumRecord> spectra_;
  bool energy_done_ = false;
  bool energy_available_ = true;  // false: an MPS history without energy columns
  long long solver_fragment_mismatches_ = -1;  // -1: the run has no fragment labels of its own
  fs::path energy_history_;       // MPS: the mapped balance terms (post/energy_history.csv)
  std::vector<std::pair<std::string, std::string>> mps_terms_;
  size_t energy_row_ = 0;
  double energy_dissipated_J_ = NAN, energy_G0_area_J_ = NAN, energy_G0_face_area_J_ = NAN, energy_G0_separating_area_J_ = NAN, energy_imbalance_ = NAN;
};

}  // namespace

PostSummary run_post(const PostOptions& options) { return Runner(options).run(); }

}  // namespace breccia::postproc
