// Distributed runs: the halo exchange, the execution space that calls it from the step, and
// the time loop's backend (mpi_backend.hpp; docs/parallel.md).
#include "breccia/solver/mpi_backend.hpp"

#include <fcntl.h>
#if defined(__GLIBC__)
#include <malloc.h>  // malloc_trim
#endif
#if __has_include(<mpi-ext.h>)
#include <mpi-ext.h>  // OpenMPI's extensions: MPIX_Query_cuda_support
#endif
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <initializer_list>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "breccia/common/error.hpp"
#include "breccia/solver/correspondence.hpp"
#include "breccia/solver/distributed_setup.hpp"
#include "breccia/solver/exec_openmp.hpp"
#include "breccia/solver/float32_state.hpp"
#include "breccia/solver/mpi_launch.hpp"
#include "breccia/solver/outputs.hpp"
#include "breccia/solver/rank_system.hpp"
#include "breccia/solver/step.hpp"
#ifdef BRECCIA_MPI_CUDA
#include "breccia/solver/cuda_backend.hpp"
#endif

namespace breccia::solver {

namespace {
int g_saved_stderr = -1;  // a quiet rank's real stderr, for the message that stops the run
}  // namespace

bool mpi_cuda_aware() {
  // BRECCIA_MPI_CUDA_AWARE=0 keeps the staged path where the library could take device memory
  // (to compare the two paths).
  if (const char* env = std::getenv("BRECCIA_MPI_CUDA_AWARE"); env && std::string(env) == "0") return false;
#if defined(MPIX_CUDA_AWARE_SUPPORT)
  // OpenMPI's CUDA extension: the headers' MPIX_CUDA_AWARE_SUPPORT says what the library they
  // came with was built with; the library loaded at run time answers for itself.
  return MPIX_Query_cuda_support() == 1;
#else
  return false;
#endif
}

MpiSession::MpiSession(int& argc, char**& argv) {
  if (!mpi_launch_from_environment().by_launcher) return;
  int provided = 0;
  // Threads inside a rank run OpenMP loops; only the main thread calls MPI.
  MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
  active_ = true;
}

MpiSession::~MpiSession() {
  if (active_) MPI_Finalize();
}

void MpiSession::quiet_other_ranks() {
  if (!active_ || rank_ == 0 || g_saved_stderr >= 0) return;
  std::fflush(stderr);
  g_saved_stderr = dup(STDERR_FILENO);
  const int devnull = open("/dev/null", O_WRONLY);
  if (devnull >= 0) {
    dup2(devnull, STDERR_FILENO);
    close(devnull);
  }
}

void MpiSession::fatal(const std::string& message, int exit_code) { mpi_abort_all(message, exit_code); }

void mpi_abort_all(const std::string& message, int exit_code) {
  int initialised = 0, rank = 0, size = 1;
  MPI_Initialized(&initialised);
  if (initialised) {
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &size);
  }
  std::fflush(stderr);
  if (g_saved_stderr >= 0) dup2(g_saved_stderr, STDERR_FILENO);
  if (size > 1) std::fprintf(stderr, "error (rank %d of %d): %s\n", rank, size, message.c_str());
  else std::fprintf(stderr, "error: %s\n", message.c_str());
  std::fflush(stderr);
  if (initialised) MPI_Abort(MPI_COMM_WORLD, exit_code);  // stops every rank: none is left waiting
  std::exit(exit_code);
}

bool mpi_all_agree(bool ok) {
  int mine = ok ? 1 : 0, all = 0;
  MPI_Allreduce(&mine, &all, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
  return all != 0;
}

namespace {

// The exchange of ghost values with the neighbouring ranks. The ghosts from one source rank
// are one contiguous run of the rank's ghosts (rank_system.hpp), and the source's send list
// to this rank holds the same particles in the same (ascending) order, so a message is
// unpacked by position. The messages (exchange_packed) are the same for the CPU, which packs
// here (exchange), and the CUDA backend, which packs on the device (halo_transport.hpp).
class HaloExchange final : public HaloTransport {
public:
  HaloExchange(const RankLayout& L, MPI_Comm comm) : comm_(comm), owned_(L.owned()) {
    for (size_t d = 0; d < L.halo.send_ranks.size(); ++d) {
      const size_t begin = send_all_.size();
      for (const int64_t j : L.halo.send_lists[d]) send_all_.push_back(static_cast<int32_t>(j - L.begin()));
      send_.push_back({L.halo.send_ranks[d], begin, send_all_.size()});
    }
    for (size_t r = 0; r < L.halo.recv_ranks.size(); ++r)
      recv_.push_back({L.halo.recv_ranks[r], L.halo.recv_begin[r], L.halo.recv_begin[r + 1]});
    ghosts_ = L.ghosts();
    check_counts(L);
    device_buffers_ = mpi_cuda_aware();
  }

  int64_t ghosts() const override { return ghosts_; }
  const std::vector<int32_t>& send_indices() const override { return send_all_; }
  bool device_buffers() const override { return device_buffers_; }

  void exchange(std::initializer_list<HaloArray> arrays) {
    HaloArrays h;
    for (const HaloArray& a : arrays) h.item[h.count++] = a;
    exchange(h);
  }

  void exchange(const HaloArrays& h) {
    const size_t per = h.bytes_per_item();
    if (per == 0) return;
    send_buf_.resize(send_all_.size() * per);
    recv_buf_.resize(static_cast<size_t>(ghosts_) * per);
    for (size_t q = 0; q < send_all_.size(); ++q) {
      char* item = send_buf_.data() + q * per;
      for (int k = 0; k < h.count; ++k) {
        const HaloArray& a = h.item[k];
        std::memcpy(item, static_cast<const char*>(a.data) + static_cast<size_t>(send_all_[q]) * a.bytes, a.bytes);
        item += a.bytes;
      }
    }
    exchange_packed(send_buf_.data(), recv_buf_.data(), per);
    for (int64_t g = 0; g < ghosts_; ++g) {
      const char* item = recv_buf_.data() + static_cast<size_t>(g) * per;
      for (int k = 0; k < h.count; ++k) {
        const HaloArray& a = h.item[k];
        std::memcpy(static_cast<char*>(a.data) + static_cast<size_t>(owned_ + g) * a.bytes, item, a.bytes);
        item += a.bytes;
      }
    }
  }

  void exchange_packed(const void* send, void* recv, size_t per) override {
    if (per == 0) return;
    requests_.resize(send_.size() + recv_.size());
    size_t req = 0;
    for (const Source& s : recv_)
      MPI_Irecv(static_cast<char*>(recv) + s.begin * per, static_cast<int>((s.end - s.begin) * per), MPI_BYTE, s.rank,
                kTag, comm_, &requests_[req++]);
    for (const Peer& p : send_)
      MPI_Isend(static_cast<const char*>(send) + p.begin * per, static_cast<int>((p.end - p.begin) * per), MPI_BYTE,
                p.rank, kTag, comm_, &requests_[req++]);
    MPI_Waitall(static_cast<int>(req), requests_.data(), MPI_STATUSES_IGNORE);
  }

  // The transpose of exchange: each ghost's value goes back to its owner, which keeps the
  // smallest of its own and every reader's (a minimum does not depend on the order of
  // arrival, so the result is exact at any rank count). One double per particle.
  void reduce_min_to_owners(double* data) {
    back_buf_.resize(send_all_.size());
    requests_.resize(send_.size() + recv_.size());
    size_t req = 0;
    for (const Peer& p : send_)  // what the peer's ghosts of these particles hold
      MPI_Irecv(back_buf_.data() + p.begin, static_cast<int>(p.end - p.begin), MPI_DOUBLE, p.rank, kBackTag, comm_,
                &requests_[req++]);
    for (const Source& s : recv_)
      MPI_Isend(data + owned_ + s.begin, static_cast<int>(s.end - s.begin), MPI_DOUBLE, s.rank, kBackTag, comm_,
                &requests_[req++]);
    MPI_Waitall(static_cast<int>(req), requests_.data(), MPI_STATUSES_IGNORE);
    for (size_t q = 0; q < send_all_.size(); ++q) data[send_all_[q]] = std::min(data[send_all_[q]], back_buf_[q]);
  }

private:
  static constexpr int kTag = 7101, kBackTag = 7102;
  struct Peer {
    int rank;
    size_t begin, end;  // its run of send_all_: the owned local indices this peer reads
  };
  struct Source {
    int rank;
    int64_t begin, end;  // its run of this rank's ghosts
  };

  // Each rank's send count to a peer must be what the peer expects to receive: the families
  // are symmetric (j in i's iff i in j's). A mismatch would mean unmatched messages and
  // wrong ghosts, so it stops the run at set-up on every rank.
  void check_counts(const RankLayout& L) {
    const int ranks = L.part.ranks();
    std::vector<long long> sends(ranks, 0), expected(ranks, 0), told(ranks, 0);
    for (const Peer& p : send_) sends[p.rank] = static_cast<long long>(p.end - p.begin);
    for (const Source& s : recv_) expected[s.rank] = s.end - s.begin;
    MPI_Alltoall(sends.data(), 1, MPI_LONG_LONG, told.data(), 1, MPI_LONG_LONG, comm_);
    int bad = told != expected ? 1 : 0, any_bad = 0;
    MPI_Allreduce(&bad, &any_bad, 1, MPI_INT, MPI_MAX, comm_);
    if (any_bad)
      throw RunError("distributed run: the bond families are not symmetric (a rank's ghosts differ from what "
                     "their owners send); this case cannot be split across ranks");
  }

  MPI_Comm comm_;
  int64_t owned_ = 0, ghosts_ = 0;
  bool device_buffers_ = false;
  std::vector<int32_t> send_all_;
  std::vector<Peer> send_;
  std::vector<Source> recv_;
  std::vector<char> send_buf_, recv_buf_;
  std::vector<double> back_buf_;
  std::vector<MPI_Request> requests_;
};

// `total` items cut into one contiguous block per rank: rank q's begins at total q / ranks.
struct Blocks {
  int64_t total;
  int ranks;
  int64_t begin(int q) const { return total * q / ranks; }
  int holding(int64_t item) const {  // the rank whose block holds `item`
    int q = static_cast<int>(item * ranks / std::max<int64_t>(total, 1));
    while (q + 1 < ranks && begin(q + 1) <= item) ++q;
    while (q > 0 && begin(q) > item) --q;
    return q;
  }
};

// An all-to-all where rank r is sent send_counts[r] consecutive elements of `type` (in rank
// order), each `per` values of T: the counts go first (MPI_Alltoall) and the displacements
// are their prefix sums. `recv` is sized to what arrives; rank r's elements start at
// recv_displs[r] (ranks + 1 entries, the last the total). Its vectors are kept between calls.
struct AllToAll {
  std::vector<int> recv_counts, send_displs, recv_displs;
  template <class T>
  void run(const T* send, const std::vector<int>& send_counts, std::vector<T>& recv, size_t per, MPI_Datatype type,
           MPI_Comm comm) {
    const size_t ranks = send_counts.size();
    recv_counts.assign(ranks, 0);
    send_displs.assign(ranks + 1, 0);
    recv_displs.assign(ranks + 1, 0);
    MPI_Alltoall(send_counts.data(), 1, MPI_INT, recv_counts.data(), 1, MPI_INT, comm);
    for (size_t r = 0; r < ranks; ++r) {
      send_displs[r + 1] = send_displs[r] + send_counts[r];
      recv_displs[r + 1] = recv_displs[r] + recv_counts[r];
    }
    recv.resize(static_cast<size_t>(recv_displs[ranks]) * per);
    MPI_Alltoallv(send, send_counts.data(), send_displs.data(), type, recv.data(), recv_counts.data(),
                  recv_displs.data(), type, comm);
  }
};

// The short-range forces' partners on other ranks (model.short_range_forces;
// contact_cells.hpp). The contact pairs are particles outside each other's family that come
// within reach as the body deforms: not the halo's ghosts, and not known before the pass. So
// at every force pass each rank sends every other rank the particles it owns that lie within
// that rank's bounding box of owned current positions grown by 1.5 x the grid's cell edge
// (the largest reach is one cell edge; the half more covers float's rounding), with what the
// contact kernel reads of them: a superset of every partner within reach, since a particle
// that is not a partner adds nothing. The receiver places them beside its own (a family
// ghost at its ghost index, so the family test still knows it; another after the ghosts)
// and builds the grid over its owned particles and the received ones listed in global
// order. Every rank owns one contiguous range of that order and sends in it, so the list is
// the received from lower ranks, the owned, the received from higher ranks: each cell is
// walked in one process's order, and an owned particle's force is one process's, bit for
// bit, at any rank count. The family test compares global indices (ContactCellsView::key):
// a rank's rows are sorted by them, and its ghosts' local indices do not follow them.
class ContactExchange {
public:
  ContactExchange(const RankLayout& L, MPI_Comm comm, double cell_edge)
      : comm_(comm), rank_(L.rank), ranks_(L.part.ranks()), owned_(L.owned()), ghosts_(L.ghosts()),
        margin_(1.5 * cell_edge), layout_(L) {}

  // The contact forces on the owned particles of `p` (the step's view: owned, then ghosts),
  // x: the owned particles' current positions in double (OpenMpExec::contact_positions).
  template <class Real>
  void pass(PdSystem& local, const PdViewT<Real>& p, const double* x) {
    constexpr size_t kReals = 9;  // x0, u, volume, spacing, short_range_k
    const size_t record = sizeof(int64_t) + 3 * sizeof(double) + kReals * sizeof(Real);
    // Every rank's box of owned current positions.
    double box[6] = {1e300, 1e300, 1e300, -1e300, -1e300, -1e300};
    for (int64_t i = 0; i < owned_; ++i)
      for (int d = 0; d < 3; ++d) {
        box[d] = std::min(box[d], x[3 * i + d]);
        box[3 + d] = std::max(box[3 + d], x[3 * i + d]);
      }
    boxes_.resize(6 * static_cast<size_t>(ranks_));
    MPI_Allgather(box, 6, MPI_DOUBLE, boxes_.data(), 6, MPI_DOUBLE, comm_);
    // The owned particles near each other rank's box, in ascending order, with their values.
    std::vector<int>& send_counts = send_counts_;
    send_counts.assign(static_cast<size_t>(ranks_), 0);
    send_.clear();
    for (int r = 0; r < ranks_; ++r) {
      if (r == rank_) continue;
      const double* b = &boxes_[6 * static_cast<size_t>(r)];
      for (int64_t i = 0; i < owned_; ++i) {
        bool near = true;
        for (int d = 0; d < 3 && near; ++d)
          near = x[3 * i + d] >= b[d] - margin_ && x[3 * i + d] <= b[3 + d] + margin_;
        if (!near) continue;
        const size_t at = send_.size();
        send_.resize(at + record);
        char* out = send_.data() + at;
        const int64_t global = layout_.begin() + i;
        put(out, &global, 1);
        put(out, &x[3 * i], 3);
        put(out, &p.x0[3 * i], 3);
        put(out, &p.u[3 * i], 3);
        put(out, &p.volume[i], 1);
        put(out, &p.spacing[i], 1);
        put(out, &p.short_range_k[i], 1);
        ++send_counts[r];
      }
    }
    MPI_Datatype type;
    MPI_Type_contiguous(static_cast<int>(record), MPI_BYTE, &type);
    MPI_Type_commit(&type);
    all_to_all_.run(send_.data(), send_counts, recv_, record, type, comm_);
    MPI_Type_free(&type);
    const std::vector<int>& recv_displs = all_to_all_.recv_displs;
    const int64_t received = recv_displs[ranks_];

    // The rank's particles (owned, then ghosts) and the received ones after them.
    Scratch<Real>& sc = scratch<Real>();
    const int64_t base = owned_ + ghosts_;
    int64_t extra = 0;
    std::vector<int64_t>& where = where_;  // each received particle's index here
    where.resize(static_cast<size_t>(received));
    for (int64_t q = 0; q < received; ++q) {
      int64_t global = 0;
      std::memcpy(&global, recv_.data() + static_cast<size_t>(q) * record, sizeof(global));
      const int64_t l = layout_.local_index(global);
      where[q] = l >= 0 ? l : base + extra++;
    }
    const int64_t total = base + extra;
    // The family test's keys: every index's global one (the rows are sorted by them).
    keys_.resize(static_cast<size_t>(total));
    for (int64_t i = 0; i < owned_; ++i) keys_[i] = static_cast<int32_t>(layout_.begin() + i);
    std::copy(layout_.halo.ghosts.begin(), layout_.halo.ghosts.end(), keys_.begin() + owned_);
    for (int64_t q = 0; q < received; ++q)
      if (where[q] >= base) {
        int64_t global = 0;
        std::memcpy(&global, recv_.data() + static_cast<size_t>(q) * record, sizeof(global));
        keys_[where[q]] = static_cast<int32_t>(global);
      }
    // The arrays the contact kernel reads, over those indices (x: the grid's positions and
    // double's bond vectors; a ghost that was not received is neither in the grid nor read).
    sc.x.resize(3 * static_cast<size_t>(total));
    std::copy(x, x + 3 * owned_, sc.x.begin());
    for (std::vector<Real>* v : {&sc.x0, &sc.u}) v->resize(3 * static_cast<size_t>(total));
    for (std::vector<Real>* v : {&sc.volume, &sc.spacing, &sc.k}) v->resize(static_cast<size_t>(total));
    std::copy(p.x0, p.x0 + 3 * base, sc.x0.begin());
    std::copy(p.u, p.u + 3 * base, sc.u.begin());
    std::copy(p.volume, p.volume + base, sc.volume.begin());
    std::copy(p.spacing, p.spacing + base, sc.spacing.begin());
    std::copy(p.short_range_k, p.short_range_k + base, sc.k.begin());
    for (int64_t q = 0; q < received; ++q) {
      const char* in = recv_.data() + static_cast<size_t>(q) * record + sizeof(int64_t);
      const size_t l = static_cast<size_t>(where[q]);
      get(in, &sc.x[3 * l], 3);
      get(in, &sc.x0[3 * l], 3);
      get(in, &sc.u[3 * l], 3);
      get(in, &sc.volume[l], 1);
      get(in, &sc.spacing[l], 1);
      get(in, &sc.k[l], 1);
    }
    // The grid's members in global order: from lower ranks, the owned, from higher ranks.
    members_.clear();
    const int64_t lower = recv_displs[rank_];
    for (int64_t q = 0; q < lower; ++q) members_.push_back(static_cast<int32_t>(where[q]));
    for (int64_t i = 0; i < owned_; ++i) members_.push_back(static_cast<int32_t>(i));
    for (int64_t q = lower; q < received; ++q) members_.push_back(static_cast<int32_t>(where[q]));

    PdViewT<Real> c = p;  // forces and energy densities: the rank's own arrays
    if constexpr (std::is_same_v<Real, double>) c.x = sc.x.data();  // double reads x, float x0 and u
    c.x0 = sc.x0.data();
    c.u = sc.u.data();
    c.volume = sc.volume.data();
    c.spacing = sc.spacing.data();
    c.short_range_k = sc.k.data();
    short_range_contact(local, c, sc.x.data(), members_, total, keys_.data());
  }

private:
  template <class Real>
  struct Scratch {
    std::vector<double> x;
    std::vector<Real> x0, u, volume, spacing, k;
  };
  template <class Real>
  Scratch<Real>& scratch() {
    if constexpr (std::is_same_v<Real, double>) return double_;
    else return float_;
  }
  template <class T>
  static void put(char*& out, const T* values, size_t count) {
    std::memcpy(out, values, count * sizeof(T));
    out += count * sizeof(T);
  }
  template <class T>
  static void get(const char*& in, T* values, size_t count) {
    std::memcpy(values, in, count * sizeof(T));
    in += count * sizeof(T);
  }

  MPI_Comm comm_;
  int rank_, ranks_;
  int64_t owned_, ghosts_;
  double margin_;
  const RankLayout& layout_;
  std::vector<double> boxes_;
  std::vector<int> send_counts_;
  AllToAll all_to_all_;
  std::vector<char> send_, recv_;
  std::vector<int64_t> where_;
  std::vector<int32_t> members_, keys_;
  Scratch<double> double_;
  Scratch<float> float_;
};

// The gas load's sums over every rank (gas.hpp, gas_fixed_order_sum). One process adds the
// wall's terms (per facet particle) and the cracks' (per particle) in blocks of kGasBlock
// items of the global index, each block from zero in index order, then the blocks in order.
// A rank owns one contiguous range of each index (the facet particles are sorted by
// particle), so a block lies wholly in one rank's range or is cut between consecutive ranks:
// each rank sends its whole blocks' sums and the terms of the items of the blocks it shares,
// every rank receives all of them in rank order, which is index order (MPI_Allgatherv), and
// adds them exactly as one process does. The sum is one process's bit for bit at any rank
// count, where adding each rank's partial sum would not be: 48 bytes per block of 256 items
// plus the cut blocks' items, every rank from every rank.
// The ranks' ranges of the facet particles come from each rank's own count (`own_facets`:
// its slice of the global list, restrict_gas), so no rank needs the global facet list.
class GasExchange {
public:
  GasExchange(const RankLayout& L, int64_t own_facets, MPI_Comm comm)
      : comm_(comm), rank_(L.rank), particles_(L.part.begin) {
    const int ranks = L.part.ranks();
    std::vector<long long> counts(static_cast<size_t>(ranks));
    long long mine = own_facets;
    MPI_Allgather(&mine, 1, MPI_LONG_LONG, counts.data(), 1, MPI_LONG_LONG, comm);
    facets_.assign(1, 0);
    for (int r = 0; r < ranks; ++r) facets_.push_back(facets_.back() + counts[r]);
  }

  // Each rank's first facet particle, and the total: the rows of the per-facet arrays.
  const std::vector<int64_t>& facet_begin() const { return facets_; }

  GasSums* terms(int64_t count) {
    terms_.resize(static_cast<size_t>(std::max<int64_t>(count, 1)));
    return terms_.data();
  }

  GasSums sum(const GasSums* terms, int64_t count, GasSumOver over) {
    const std::vector<int64_t>& begin = over == GasSumOver::Facets ? facets_ : particles_;
    const int ranks = static_cast<int>(begin.size()) - 1;
    if (count != begin[rank_ + 1] - begin[rank_]) throw std::logic_error("distributed gas: a rank's item count");
    mine_.clear();
    counts_.resize(static_cast<size_t>(ranks));
    displs_.resize(static_cast<size_t>(ranks));
    int total = 0;
    for (int r = 0; r < ranks; ++r) {
      counts_[r] = static_cast<int>(records(begin, r, r == rank_ ? terms : nullptr));
      displs_[r] = total;
      total += counts_[r];
    }
    all_.resize(static_cast<size_t>(std::max(total, 1)));
    MPI_Datatype type;
    MPI_Type_contiguous(static_cast<int>(sizeof(GasSums)), MPI_BYTE, &type);
    MPI_Type_commit(&type);
    MPI_Allgatherv(mine_.data(), counts_[rank_], type, all_.data(), counts_.data(), displs_.data(), type, comm_);
    MPI_Type_free(&type);
    // One process's additions (GasBlockSum, then gas_fixed_order_sum's fold of the blocks).
    const int64_t n = begin.back();
    GasSums sum{};
    size_t at = 0;
    for (int64_t lo = 0; lo < n; lo += kGasBlock) {
      const int64_t hi = std::min(lo + kGasBlock, n);
      const int r = static_cast<int>(std::upper_bound(begin.begin(), begin.end(), lo) - begin.begin()) - 1;
      if (hi <= begin[r + 1]) {  // wholly rank r's: its sum
        sum = gas_sums_add(sum, all_[at++]);
      } else {
        GasSums block{};
        for (int64_t i = lo; i < hi; ++i) block = gas_sums_add(block, all_[at++]);
        sum = gas_sums_add(sum, block);
      }
    }
    return sum;
  }

private:
  // Rank r's records: per block meeting its range, the block's sum if the block is wholly
  // its own, else its items' terms. With `terms` (this rank's) they go to mine_; the count
  // alone otherwise (every rank counts every rank's from the ranges).
  int64_t records(const std::vector<int64_t>& begin, int r, const GasSums* terms) {
    const int64_t b = begin[r], e = begin[r + 1], n = begin.back();
    int64_t count = 0;
    for (int64_t lo = b; lo < e;) {
      const int64_t block = lo - lo % kGasBlock, block_end = std::min(block + kGasBlock, n), hi = std::min(block_end, e);
      if (block >= b && block_end <= e) {
        if (terms) {
          GasSums acc{};
          for (int64_t i = block; i < block_end; ++i) acc = gas_sums_add(acc, terms[i - b]);
          mine_.push_back(acc);
        }
        ++count;
      } else {
        if (terms) mine_.insert(mine_.end(), terms + (lo - b), terms + (hi - b));
        count += hi - lo;
      }
      lo = hi;
    }
    return count;
  }

  MPI_Comm comm_;
  int rank_;
  std::vector<int64_t> particles_, facets_;  // each rank's first item, and the total
  std::vector<GasSums> terms_, mine_, all_;
  std::vector<int> counts_, displs_;
};

// The CPU's execution space plus the exchanges a distributed step needs (step.hpp).
class MpiExec : public OpenMpExec {
public:
  MpiExec(PdSystem& local, HaloExchange& halo, ContactExchange* contact, GasExchange* gas)
      : OpenMpExec(local), local_(local), halo_(halo), contact_(contact), gas_(gas) {}

  // The gas load over ranks (gas.hpp GasOnRanks).
  static constexpr bool kGasRanks = true;
  // The front and the crack pass read the ghosts' positions: their displacement now (the
  // force pass's exchange comes after the loads), and whether they are debris (GasAttached).
  int64_t gas_ghosts(const PdView& d, const GasView& g) const {
    halo_.exchange({{d.u, 3 * sizeof(double)}, {g.attached, sizeof(uint8_t)}});
    return halo_.ghosts();
  }
  // A dry ghost reached from this rank's particles is reached on its owner's rank: the
  // smallest arrival time of every rank's goes to the owner, then the owner's to every
  // ghost, which is committed there as the crack pass commits the owned ones.
  void gas_front_to_ghosts(const GasView& g) const {
    halo_.reduce_min_to_owners(g.arrival_next);
    halo_.exchange({{g.arrival_next, sizeof(double)}});
    const int64_t owned = static_cast<int64_t>(local_.n);
    std::copy(g.arrival_next + owned, g.arrival_next + owned + halo_.ghosts(), g.arrival + owned);
  }
  GasSums* gas_rank_terms(int64_t count) const { return gas().terms(count); }
  GasSums gas_sum_over_ranks(const GasSums* terms, int64_t count, GasSumOver over) const {
    return gas().sum(terms, count, over);
  }

  // The short-range forces with the other ranks' particles near this rank's (ContactExchange).
  template <class Real>
  void contact(const StepArrays<Real>& a) const {
    if (!contact_) throw std::logic_error("distributed run: short-range forces without their exchange");
    contact_->pass(local_, a.p, contact_positions(a));
  }

  // The minimum stretches the coming pass reads: the owners' values of the last pass.
  template <class Real>
  void commit_min_stretch(StepArrays<Real>& a) const {
    OpenMpExec::commit_min_stretch(a);
    if (!local_.min_stretch.empty()) halo_.exchange({{local_.min_stretch.data(), sizeof(float)}});
  }

  template <class Real>
  void exchange(const StepArrays<Real>& a, HaloField field) const {
    halo_.exchange(halo_arrays(a, field, local_.config.strength_rate != StrengthRateLaw::None));
  }

private:
  GasExchange& gas() const {
    if (!gas_) throw std::logic_error("distributed run: a gas load without its exchange");
    return *gas_;
  }

  PdSystem& local_;
  HaloExchange& halo_;
  ContactExchange* contact_;
  GasExchange* gas_;
};

// Each rank's elements [begin[r], begin[r + 1]) of an array, in elements of `bytes` (a
// derived type, so a rank's range may pass 2^31 bytes).
struct ElementRanges {
  MPI_Datatype type;
  std::vector<int> counts, displs;
  ElementRanges(size_t bytes, const std::vector<int64_t>& begin) {
    MPI_Type_contiguous(static_cast<int>(bytes), MPI_BYTE, &type);
    MPI_Type_commit(&type);
    for (size_t r = 0; r + 1 < begin.size(); ++r) {
      counts.push_back(static_cast<int>(begin[r + 1] - begin[r]));
      displs.push_back(static_cast<int>(begin[r]));
    }
  }
  ~ElementRanges() { MPI_Type_free(&type); }
  ElementRanges(const ElementRanges&) = delete;
  ElementRanges& operator=(const ElementRanges&) = delete;
};

// Every rank's range of `data` to every rank, in place.
void allgather_ranges(void* data, size_t bytes, const std::vector<int64_t>& begin, MPI_Comm comm) {
  const ElementRanges e(bytes, begin);
  MPI_Allgatherv(MPI_IN_PLACE, 0, MPI_DATATYPE_NULL, data, e.counts.data(), e.displs.data(), e.type, comm);
}

// Rank 0 receives every rank's range (the rank's own, from the start of `local`) into
// `global`. `held`: whether rank 0 holds `global` (the feature is on), the same on every
// rank, so every rank takes part or none; the other ranks need not hold it (their global
// system lets go of the gathers' targets: release_global_for_loop).
template <class T, class A>
void gather_ranges(const std::vector<T, A>& local, std::vector<T, A>& global, const std::vector<int64_t>& begin, int rank,
                   MPI_Comm comm, bool held) {
  if (!held) return;
  const ElementRanges e(sizeof(T), begin);
  MPI_Gatherv(local.data(), e.counts[rank], e.type, global.data(), e.counts.data(), e.displs.data(), e.type, 0, comm);
}

// The ranks' element ranges of a per-particle array of `width` values each, and of a
// per-entry array (a rank's owned rows are one contiguous run of entries).
std::vector<int64_t> particle_ranges(const Partition& part, size_t width) {
  std::vector<int64_t> begin;
  for (const int64_t b : part.begin) begin.push_back(b * static_cast<int64_t>(width));
  return begin;
}
// A finished distributed set-up's global system holds them (PdSystem::distributed_entries;
// no row offsets on the ranks other than 0).
std::vector<int64_t> entry_ranges(const Partition& part, const PdSystem& g) {
  if (!g.distributed_entries.empty()) return g.distributed_entries;
  std::vector<int64_t> begin;
  for (const int64_t b : part.begin) begin.push_back(g.offsets[b]);
  return begin;
}

// The rank's share of the run: its layout, its system and its halo exchange. Built once per
// run: by the set-up's stable-step estimate, whose force passes run on it, then handed to the
// time loop's (or dynamic relaxation's) backend, which brings its state up to date
// (copy_rank_state) instead of building it again.
struct RankShare {
  RankLayout layout;
  PdSystem local;
  std::unique_ptr<HaloExchange> halo;
  std::unique_ptr<ContactExchange> contact;  // model.short_range_forces only
  std::unique_ptr<GasExchange> gas;          // a gas load only
  size_t global_n = 0, global_bonds = 0;  // of the system it was cut from
  size_t body_n = 0;                      // the whole body's particles (PdSystem::whole_n)
};

// take_bonds: a distributed set-up's global system, whose bonds are the rank's own: they move
// into the rank's system instead of being copied (restrict_to_rank_taking_bonds).
std::shared_ptr<RankShare> make_rank_share(const PdSystem& global, MPI_Comm comm, PdSystem* take_bonds = nullptr) {
  int rank = 0, size = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  auto sh = std::make_shared<RankShare>();
  sh->layout = rank_layout(global, size, rank);
  sh->local = take_bonds ? restrict_to_rank_taking_bonds(*take_bonds, sh->layout) : restrict_to_rank(global, sh->layout);
  sh->halo = std::make_unique<HaloExchange>(sh->layout, comm);
  if (!sh->local.short_range_k.empty())
    sh->contact = std::make_unique<ContactExchange>(sh->layout, comm, sh->local.contact_cell_edge);
  if (global.gas.active)
    sh->gas = std::make_unique<GasExchange>(sh->layout, static_cast<int64_t>(sh->local.gas.wall_dv.size()), comm);
  sh->global_n = global.n;
  sh->global_bonds = global.bond_count();
  sh->body_n = global.whole_n();
  return sh;
}

// What the set-up's estimate built, waiting for the backend (one run per process).
std::shared_ptr<RankShare> g_setup_share;

// The set-up's share with its state brought up to date, or (none, or cut from another
// system) a new one. Collective: every rank takes the same branch, since every rank holds
// the same global system and ran the same set-up.
std::shared_ptr<RankShare> take_rank_share(const PdSystem& global, MPI_Comm comm) {
  std::shared_ptr<RankShare> sh = std::move(g_setup_share);
  g_setup_share.reset();
  // A distributed set-up's share was cut from its global system before the bonds left it
  // (finish_distributed_setup): the bond count it saw was the rank's own.
  if (sh && sh->global_n == global.n && (sh->global_bonds == global.bond_count() || !global.distributed_rows.empty())) {
    copy_rank_state(sh->local, global, sh->layout);
    return sh;
  }
  return make_rank_share(global, comm);
}

#ifdef BRECCIA_MPI_CUDA
// This process's place among the ranks on its node (MPI_COMM_TYPE_SHARED): which GPU it takes.
int node_local_rank(MPI_Comm comm) {
  MPI_Comm node;
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_split_type(comm, MPI_COMM_TYPE_SHARED, rank, MPI_INFO_NULL, &node);
  int local = 0;
  MPI_Comm_rank(node, &local);
  MPI_Comm_free(&node);
  return local;
}
#endif

// --backend cuda: which device each rank took and how the halo travels, printed by rank 0
// (collective: every rank sends its device's index).
void print_rank_devices(MPI_Comm comm, bool progress) {
#ifdef BRECCIA_MPI_CUDA
  int rank = 0, ranks = 1, device = cuda_device_in_use();
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &ranks);
  std::vector<int> devices(static_cast<size_t>(ranks));
  MPI_Gather(&device, 1, MPI_INT, devices.data(), 1, MPI_INT, 0, comm);
  if (rank != 0 || !progress) return;
  std::string list;
  for (int r = 0; r < ranks; ++r) list += (r ? ", " : "") + std::to_string(devices[r]);
  std::fprintf(stderr, "  CUDA device: %s; devices by rank: %s; halo: %s\n", cuda_device_description().c_str(),
               list.c_str(), mpi_cuda_aware() ? "device buffers (CUDA-aware MPI)" : "staged through pinned host buffers");
#else
  (void)comm, (void)progress;
#endif
}

// The rank's step: on the CPU (MpiExec), or with `cuda` on a GPU (a CudaSystem of the rank's
// system, the halo packed on the device and carried by the same HaloExchange's messages).
// Everything else (the sums over ranks, the gathers, the files) is the same code either way.
class MpiBackend final : public StepBackend {
public:
  MpiBackend(PdSystem& global, MPI_Comm comm, bool cuda = false)
      : comm_(comm), share_(take_rank_share(global, comm)) {
    if (global.derived_fields_pending) {
      restart_ghosts(global);
      // read_checkpoint's pass at the restored state, on the rank's particles (no bond
      // breaks: the stretches are the checkpointed step's); forces and the dissipated
      // energy stay the checkpoint's.
      // With a rate law the bond states are kept as checkpointed (CheckpointedPassState).
      CheckpointedPassState checkpointed(local_);
      local_.diagnostics = true;
      force_pass(local_);
      checkpointed.restore(local_);
      global.derived_fields_pending = false;
    }
    // Every rank's system now holds its share: the global one keeps what the loop and the
    // writers read, the whole state on rank 0 only (release_global_for_loop). Before any
    // gather: a rank other than 0 may never have held a gather's target (`u`, `v`, `a`, `body`:
    // release_global_for_loop names them as held, so it takes part as rank 0 does).
    released_ = release_global_for_loop(global, layout_.rank == 0, &local_);
#if defined(__GLIBC__)
    malloc_trim(0);  // the freed pages back to the system (glibc's heap would keep them resident)
#endif
    // float32: one process's first measure leaves the float-rounded kinematics in its system,
    // which the first output writes (run_time_loop); later outputs download first anyway.
    if (local_.f32.active) {
      kinematics_to_host();
      gather_kinematics(global);  // rank 0's staging (serial HDF5); with parallel HDF5 nothing is held
    }
    if (cuda) {
#ifdef BRECCIA_MPI_CUDA
      check_cuda_ranks_support(local_.config, "the case");  // breccia-solve refused these before set-up
      cuda_use_device(node_local_rank(comm_));
      device_ = make_cuda_rank_backend(local_, halo_.get());  // uploads the state as it is now
#else
      throw InputError("--backend", "cuda", "cuda under mpirun", "cpu (this build's MPI backend has no CUDA)");
#endif
    }
  }

  // A distributed restart: each rank read its owned rows of the checkpoint's per-particle
  // datasets (read_checkpoint), which its system took with zeros for the ghosts
  // (copy_rank_state); the ghosts' values come from their owners here, the same doubles as
  // the file's rows. The rows each rank read go to rank 0 (summary.json's
  // restart_rows_per_rank). Collective.
  void restart_ghosts(PdSystem& global) {
    PdSystem& s = local_;
    constexpr size_t v3 = 3 * sizeof(double);
    halo_->exchange({{s.u.data(), v3}, {s.v.data(), v3}, {s.a.data(), v3}});
    halo_->exchange({{s.force.data(), v3}, {s.body.data(), v3}});
    if (!s.min_stretch.empty())
      halo_->exchange({{s.min_stretch.data(), sizeof(s.min_stretch[0])},
                       {s.min_stretch_next.data(), sizeof(s.min_stretch_next[0])}});
    if (s.gas.active && s.gas.crack_entry) {
      GasState& g = s.gas;
      if (g.push.empty()) halo_->exchange({{g.arrival.data(), sizeof(double)}});
      else halo_->exchange({{g.arrival.data(), sizeof(double)}, {g.push.data(), v3}});
      g.arrival_next = g.arrival;  // as read_checkpoint leaves it
    }
    if (s.f32.active) {  // float32_enable converted the rows with the ghosts' zeros: again, as it does
      float32_upload(s);
      s.f32.force.assign(s.force.begin(), s.force.end());
    }
    const int64_t mine = global.restart_rows.empty() ? 0 : global.restart_rows[0];
    global.restart_rows.assign(static_cast<size_t>(layout_.part.ranks()), 0);
    MPI_Gather(&mine, 1, MPI_INT64_T, global.restart_rows.data(), 1, MPI_INT64_T, 0, comm_);
  }

  void step(PdSystem& g) override {
    local_.diagnostics = g.diagnostics;
    if (device_) {
      device_->step(local_);
    } else {
      MpiExec exec(local_, *halo_, share_->contact.get(), share_->gas.get());
      with_step_arrays(local_, [&](auto& a) { pd_step(exec, a, local_); });
    }
    g.time = local_.time;
    g.step = local_.step;
    std::copy(local_.indenter_position, local_.indenter_position + 3, g.indenter_position);
    if (local_.gas.active) g.gas.copy_scalars(local_.gas);  // every rank's alike (GasExchange)
  }

  // --kernel-times: each rank's device times its own launches; rank 0's are the summary's.
  bool time_kernels(long long warmup_steps) override { return device_ && device_->time_kernels(warmup_steps); }
  std::optional<KernelTimes> kernel_times() override { return device_ ? device_->kernel_times() : std::nullopt; }
  std::optional<DeviceMemory> device_memory() override { return device_ ? device_->device_memory() : std::nullopt; }

  void compute_forces(PdSystem&) override {
    local_.diagnostics = true;
    if (device_) return device_->compute_forces(local_);  // the fields stay there until a download
    force_pass(local_);
    if (local_.f32.active) float32_download(local_);
  }

  // Sums over ranks: energies to rounding (the order of the sum differs from one process's),
  // counts and the largest damage exactly; the accumulators into the global system.
  // On a GPU the rank's sums are the device's (as on one process with --backend cuda), then
  // taken over ranks here alike.
  Energies measure(PdSystem& g) override {
    if (!device_ && local_.f32.active) float32_download_kinematics(local_);  // the float state is the truth
    const Energies e = device_ ? device_->measure(local_) : solver::measure(local_);
    double sums[4] = {e.kinetic, e.strain, local_.external_work, local_.dissipated_energy}, total[4];
    MPI_Allreduce(sums, total, 4, MPI_DOUBLE, MPI_SUM, comm_);
    double dmax = e.max_damage, gmax = 0.0;
    MPI_Allreduce(&dmax, &gmax, 1, MPI_DOUBLE, MPI_MAX, comm_);
    // The history counts the particles the gas has reached: each rank its own particles'
    // arrival times (the owners'), summed (a count: exact in any order).
    long long wetted = 0;
    if (local_.gas.crack_entry)
      for (size_t i = 0; i < local_.n; ++i) wetted += local_.gas.arrival[i] < 1e300;
    long long counts[3] = {e.broken_half_bonds, e.finite ? 0 : 1, wetted}, gcounts[3];
    MPI_Allreduce(counts, gcounts, 3, MPI_LONG_LONG, MPI_SUM, comm_);
    long long bad = e.bad_particle >= 0 ? e.bad_particle + layout_.begin() : -1, gbad = -1;
    MPI_Allreduce(&bad, &gbad, 1, MPI_LONG_LONG, MPI_MAX, comm_);
    Energies out;
    out.kinetic = total[0];
    out.strain = total[1];
    out.max_damage = gmax;
    out.broken_half_bonds = gcounts[0];
    out.finite = gcounts[1] == 0;
    out.bad_particle = gbad;
    out.gas_wetted = local_.gas.crack_entry ? gcounts[2] : -1;
    g.external_work = total[2];
    g.dissipated_energy = total[3];
    return out;
  }

  // The rank's state to its host system and, with serial HDF5, gathered into rank 0's global
  // system, whose writers write every file from it (its staging). With parallel HDF5 every rank
  // writes its own rows (checkpoint, output) and the history's particles and the instability
  // message come from their owners (history_particles, instability): nothing is gathered, and
  // no rank holds the whole state (release_global_for_loop).
  void download(PdSystem& g) override {
    to_host();
#ifdef BRECCIA_PARALLEL_HDF5
    (void)g;
#else
    const std::vector<int64_t> one = particle_ranges(layout_.part, 1), three = particle_ranges(layout_.part, 3),
                               nine = particle_ranges(layout_.part, 9), entries = entry_ranges(layout_.part, g);
    for (auto [l, gl] : {std::pair{&local_.u, &g.u}, {&local_.v, &g.v}, {&local_.a, &g.a}, {&local_.force, &g.force},
                         {&local_.body, &g.body}})
      gather(*l, *gl, three);
    for (auto [l, gl] : {std::pair{&local_.energy_density, &g.energy_density}, {&local_.dissipated, &g.dissipated},
                         {&local_.damage, &g.damage}, {&local_.max_stretch, &g.max_stretch},
                         {&local_.dilatation, &g.dilatation}, {&local_.lps_a, &g.lps_a}, {&local_.lps_b, &g.lps_b},
                         {&local_.corr_nonaffine, &g.corr_nonaffine}})
      gather(*l, *gl, one);
    gather(local_.corr_deformation, g.corr_deformation, nine);
    gather(local_.corr_force_tensor, g.corr_force_tensor, nine);
    gather(local_.min_stretch, g.min_stretch, one);
    gather(local_.min_stretch_next, g.min_stretch_next, one);
    gather(local_.state, g.state, entries);
    gather(local_.bond_damage, g.bond_damage, entries);
    if (local_.config.strength_rate != StrengthRateLaw::None) gather(local_.s_onset, g.s_onset, entries);
    if (local_.gas.active) {  // what checkpoint.h5 keeps of the gas (write_checkpoint)
      const std::vector<int64_t>& facets = share_->gas->facet_begin();
      gather(local_.gas.wall_dv, g.gas.wall_dv, facets);
      gather(local_.gas.wall_on, g.gas.wall_on, facets);
      gather(local_.gas.arrival, g.gas.arrival, one);
      gather(local_.gas.in_crack, g.gas.in_crack, entries);
      // Between two crack passes: the vectors the volume follows (/gas/push).
      if (local_.gas.crack_pass_every > 1) gather(local_.gas.push, g.gas.push, three);
    }
#endif
  }

#ifdef BRECCIA_PARALLEL_HDF5
  void output(PdSystem& g, ResultsWriter* results, const std::string& out_dir) override {
    if (!g.config.write_results) return StepBackend::output(g, results, out_dir);
    to_host();
    write_output(g, results, out_dir);
  }

  // The set-up's state, as every rank's system holds it (copy_rank_state: the global
  // system's values, float32's kinematics rounded as download_kinematics left them), written
  // together like any output: no rank holds the whole bond state to write it alone.
  void first_output(PdSystem& g, ResultsWriter* results, const std::string& out_dir) override {
    if (g.config.write_results) write_output(g, results, out_dir);
  }

  // Every rank writes rows of results.h5's output group: the file's rows are cut into one
  // contiguous block per rank (file_rows), and the owned particles' values travel to the rank
  // whose block holds their file index (file_blocks). The broken bits by blocks too
  // (broken_bits_together): no rank gathers the bond states or the whole bits.
  void write_output(PdSystem& g, ResultsWriter* results, const std::string& out_dir) {
    const int r = layout_.rank;
    std::vector<Column> columns;
    for (const ResultsField& f : results_fields(g)) columns.push_back({(local_.*f.values).data(), f.components});
    const Blocks rows_of = file_rows(g);
    const std::vector<std::vector<double>> rows = file_blocks(columns, rows_of);
    const int64_t file_first = rows_of.begin(r), file_count = rows_of.begin(r + 1) - file_first;
    long long broken_count = 0;
    const Blocks bytes = bit_bytes(file_bond_offsets(g).bonds);
    const std::vector<uint8_t> broken = broken_bits_together(g, bytes, &broken_count);
    ResultsWriter::write_together(g, results, out_dir, static_cast<size_t>(file_first), static_cast<size_t>(file_count),
                                  rows, broken, static_cast<size_t>(bytes.begin(r)), static_cast<size_t>(bytes.total),
                                  broken_count, comm_);
  }

  // The particle file's rows, one contiguous block per rank: which rank writes which rows of
  // results.h5's per-particle datasets.
  Blocks file_rows(const PdSystem& g) const { return Blocks{static_cast<int64_t>(g.whole_n()), layout_.part.ranks()}; }

  // A per-particle array of the rank's system (internal order): `components` values per row,
  // the owned rows first.
  struct Column {
    const double* values;
    int components;
  };
  // This rank's block (`rows_of`: file_rows) of each column in the particle file's order: the
  // owned rows' values travel to the rank whose block holds their file index (one all-to-all,
  // every column at once). Collective.
  std::vector<std::vector<double>> file_blocks(const std::vector<Column>& columns, const Blocks& rows_of) {
    const int r = layout_.rank, size = rows_of.ranks;
    size_t width = 1;  // per particle: its file index, then every column's components
    for (const Column& c : columns) width += static_cast<size_t>(c.components);
    const int64_t owned = layout_.owned();
    std::vector<int> send_counts(size, 0), at(size, 0);  // at: where each block's values go in `send`
    for (int64_t k = 0; k < owned; ++k)
      send_counts[rows_of.holding(local_.original_index[k])] += static_cast<int>(width);
    for (int q = 1; q < size; ++q) at[q] = at[q - 1] + send_counts[q - 1];
    std::vector<double> send(static_cast<size_t>(at[size - 1] + send_counts[size - 1])), recv;
    for (int64_t k = 0; k < owned; ++k) {
      const int64_t fi = local_.original_index[k];  // the rank's own: the global list is rank 0's
      int& next = at[rows_of.holding(fi)];
      double* out = send.data() + next;
      next += static_cast<int>(width);
      *out++ = static_cast<double>(fi);  // exact: file indices stay below 2^53
      for (const Column& col : columns)
        for (int c = 0; c < col.components; ++c) *out++ = col.values[static_cast<size_t>(col.components * k + c)];
    }
    AllToAll().run(send.data(), send_counts, recv, 1, MPI_DOUBLE, comm_);
    const int64_t file_first = rows_of.begin(r), file_count = rows_of.begin(r + 1) - file_first;
    std::vector<std::vector<double>> rows(columns.size());
    for (size_t f = 0; f < columns.size(); ++f) rows[f].resize(static_cast<size_t>(file_count * columns[f].components));
    for (size_t at = 0; at < recv.size(); at += width) {
      const int64_t row = static_cast<int64_t>(recv[at]) - file_first;
      size_t c0 = at + 1;
      for (size_t f = 0; f < columns.size(); ++f)
        for (int c = 0; c < columns[f].components; ++c) rows[f][static_cast<size_t>(columns[f].components * row + c)] = recv[c0++];
    }
    return rows;
  }

  // results.h5's /particles, when the root's writer left them to the ranks (a new file:
  // particles_pending), written by every rank together: its owned rows' reference positions,
  // volumes, densities, horizons and materials (its system's: the set-up's values, the same
  // doubles as the particle file's and the global system's) moved to the file's blocks
  // (file_blocks, as an output's fields). No rank holds the whole arrays. Collective.
  void results_particles(PdSystem& g, ResultsWriter* results, const std::string& out_dir) {
    if (!g.config.write_results) return;
    int pending = results && results->particles_pending() ? 1 : 0;
    MPI_Bcast(&pending, 1, MPI_INT, 0, comm_);
    if (!pending) return;
    const int r = layout_.rank;
    const size_t owned = static_cast<size_t>(layout_.owned());
    const std::vector<double> material(local_.material.begin(), local_.material.begin() + owned);  // exact
    const Blocks rows_of = file_rows(g);
    const std::vector<std::vector<double>> rows =
        file_blocks({{local_.x0.data(), 3}, {local_.volume.data(), 1}, {local_.density.data(), 1},
                     {local_.horizon.data(), 1}, {material.data(), 1}},
                    rows_of);
    const int64_t file_first = rows_of.begin(r);
    ResultsWriter::write_particles_together(results, out_dir, static_cast<size_t>(file_first),
                                            static_cast<size_t>(rows_of.begin(r + 1) - file_first), rows, g.whole_n(),
                                            comm_);
  }

  // This rank's block (`bytes`: bit_bytes) of the output group's broken bits (one per bond of
  // results.h5's bond list; each rank writes its block of the dataset), without the bond
  // states leaving their ranks: each rank finds its own rows' broken bonds' places in the
  // file's list (broken_bond_positions) and the ranks form the blocks from them (bit_block).
  // No rank holds the whole bits (1 bit per bond: 750 MB at 6e9 bonds); the most bytes of
  // them each rank held go to rank 0 (summary.json's broken_bits_bytes_per_rank). Collective.
  std::vector<uint8_t> broken_bits_together(PdSystem& g, const Blocks& bytes, long long* count) {
    const FileBondOffsets& offsets = file_bond_offsets(g);
    std::vector<int64_t> mine =
        broken_bond_positions(local_, static_cast<size_t>(layout_.owned()), offsets.row_first, g.precrack_pairs);
    long long total = static_cast<long long>(mine.size());
    MPI_Allreduce(MPI_IN_PLACE, &total, 1, MPI_LONG_LONG, MPI_SUM, comm_);
    *count = total;
    std::vector<uint8_t> block = bit_block(std::move(mine), offsets.bonds, true, bytes);
    broken_bits_held_ = std::max(broken_bits_held_, static_cast<int64_t>(block.size()));
    g.broken_bits_bytes.assign(static_cast<size_t>(bytes.ranks), 0);
    MPI_Gather(&broken_bits_held_, 1, MPI_INT64_T, g.broken_bits_bytes.data(), 1, MPI_INT64_T, 0, comm_);
    return block;
  }

  // The bytes of `bits` bits (one per bond of the file's list), one contiguous block per rank.
  Blocks bit_bytes(int64_t bits) const { return Blocks{(bits + 7) / 8, layout_.part.ranks()}; }

  // This rank's block (`bytes`: bit_bytes) of a bit array of `bits` bits formed by every rank
  // together: each rank sends the places it holds to the rank whose block holds them (one
  // all-to-all, 8 bytes per place), which sets them in a clear block (`set`) or clears them in
  // a block of ones (the bits past `bits`, in the last byte, stay clear). Collective.
  std::vector<uint8_t> bit_block(std::vector<int64_t> places, int64_t bits, bool set, const Blocks& bytes) {
    std::sort(places.begin(), places.end());  // ascending places: ascending blocks
    std::vector<int> send_counts(static_cast<size_t>(bytes.ranks), 0);
    for (const int64_t at : places) ++send_counts[bytes.holding(at >> 3)];
    std::vector<int64_t> received;
    AllToAll().run(places.data(), send_counts, received, 1, MPI_INT64_T, comm_);
    const int64_t first = bytes.begin(layout_.rank), end = bytes.begin(layout_.rank + 1);
    std::vector<uint8_t> block(static_cast<size_t>(end - first), 0);
    if (!set)
      for (int64_t at = 8 * first; at < std::min(8 * end, bits); ++at)
        block[(at >> 3) - first] |= static_cast<uint8_t>(1u << (at & 7));
    for (const int64_t at : received) {
      const uint8_t b = static_cast<uint8_t>(1u << (at & 7));
      if (set) block[(at >> 3) - first] |= b;
      else block[(at >> 3) - first] &= static_cast<uint8_t>(~b);
    }
    return block;
  }

  // results.h5's bond list, when the root's writer left it to the ranks (a new file:
  // bonds_pending), written by every rank together: each rank forms its own rows
  // (file_bond_rows: its rows' partners, in the file's order, at their places, which the
  // list's offsets give: file_bond_offsets) and writes them as its runs of /bonds/neighbors,
  // its block of the offsets' rows, and its block of the within_horizon bits (bit_block, from
  // the places of its pad bonds, which lie beyond both horizons: about a quarter of the bonds
  // on a lattice with m = 3.015). No rank gathers a partner or the whole offsets. On a restart
  // the root checks its file's list against the count (check_bond_count). Collective.
  void results_bonds(PdSystem& g, ResultsWriter* results, const std::string& out_dir) {
    if (!g.config.write_results) return;
    const FileBondOffsets& offsets = file_bond_offsets(g);
    // The offsets this rank holds (its block and its rows' first places), to rank 0
    // (summary.json's file_offsets_rows_per_rank).
    const int64_t held = static_cast<int64_t>(offsets.block.size() + offsets.row_first.size());
    g.file_offsets_rows.assign(static_cast<size_t>(layout_.part.ranks()), 0);
    MPI_Gather(&held, 1, MPI_INT64_T, g.file_offsets_rows.data(), 1, MPI_INT64_T, 0, comm_);
    int pending = results && results->bonds_pending() ? 1 : 0;
    MPI_Bcast(&pending, 1, MPI_INT, 0, comm_);
    if (results) results->check_bond_count(offsets.bonds);
    if (!pending) return;
    const int r = layout_.rank;
    FileBondRows mine = file_bond_rows(local_, static_cast<size_t>(layout_.owned()), offsets.row_first);
    const Blocks bytes = bit_bytes(offsets.bonds);
    const std::vector<uint8_t> within = bit_block(std::move(mine.beyond_horizon), offsets.bonds, false, bytes);
    ResultsWriter::write_bonds_together(results, out_dir, offsets.block, static_cast<size_t>(offsets.block_first),
                                        g.whole_n() + 1, offsets.bonds, mine, within,
                                        static_cast<size_t>(bytes.begin(r)), comm_);
#if defined(__GLIBC__)
    mine = FileBondRows{};
    malloc_trim(0);  // the rows' staging back to the system, as after the set-up (glibc keeps freed pages)
#endif
  }

  // results.h5's /bonds/offsets (HalfBondList::offsets, n + 1 rows) without the whole array on
  // any rank, formed once (the bond lists do not change): the rows are cut into one contiguous
  // block per rank (Blocks, as the output groups' rows), each rank sends each own row's (file
  // index, count of partners of higher file index: half_bond_counts) to the rank whose block
  // holds that file index (one all-to-all), the block's first offset is the sum of the lower
  // blocks' counts (MPI_Exscan) and its others a prefix sum within it; then each rank gets
  // back its own rows' first places in answer to the same messages (the reverse all-to-all,
  // 8 bytes per row). Counts: exact. Held per rank: its block and its own rows, O(n / ranks).
  struct FileBondOffsets {
    int64_t block_first = 0;          // the block's first row of /bonds/offsets
    std::vector<int64_t> block;       // /bonds/offsets rows [block_first, block_first + size)
    std::vector<int64_t> row_first;   // own row i's first place in the list (internal order)
    int64_t bonds = -1;               // the list's length (the offsets' last row)
  };
  const FileBondOffsets& file_bond_offsets(const PdSystem& g) {
    FileBondOffsets& o = file_bond_offsets_;
    if (o.bonds >= 0) return o;
    const int ranks = layout_.part.ranks(), r = layout_.rank;
    const size_t owned = static_cast<size_t>(layout_.owned());
    const Blocks rows{static_cast<int64_t>(g.whole_n()) + 1, ranks};
    const std::vector<int64_t> counts = half_bond_counts(local_, owned);
    std::vector<int> send_counts(static_cast<size_t>(ranks), 0), at(static_cast<size_t>(ranks), 0);
    for (size_t k = 0; k < owned; ++k) ++send_counts[rows.holding(local_.original_index[k])];
    for (int q = 1; q < ranks; ++q) at[q] = at[q - 1] + send_counts[q - 1];
    std::vector<int64_t> send(2 * owned), recv;  // (file index, count) per own row, by block
    for (size_t k = 0; k < owned; ++k) {
      const int64_t fi = local_.original_index[k];
      int64_t* out = send.data() + 2 * static_cast<size_t>(at[rows.holding(fi)]++);
      out[0] = fi;
      out[1] = counts[k];
    }
    MPI_Datatype pair;
    MPI_Type_contiguous(2, MPI_INT64_T, &pair);
    MPI_Type_commit(&pair);
    AllToAll exchange;
    exchange.run(send.data(), send_counts, recv, 2, pair, comm_);
    MPI_Type_free(&pair);
    // The block: row fi + 1 - block_first first holds row fi's count, then the prefix sum.
    o.block_first = rows.begin(r);
    o.block.assign(static_cast<size_t>(rows.begin(r + 1) - o.block_first), 0);
    int64_t total = 0;  // the block's rows' counts: the next block's first offset less this one's
    for (size_t k = 0; k < recv.size(); k += 2) {
      const size_t row = static_cast<size_t>(recv[k] - o.block_first);
      if (row + 1 < o.block.size()) o.block[row + 1] = recv[k + 1];
      total += recv[k + 1];
    }
    int64_t base = 0;
    MPI_Exscan(&total, &base, 1, MPI_INT64_T, MPI_SUM, comm_);
    if (r == 0) base = 0;  // MPI_Exscan leaves rank 0's undefined
    if (!o.block.empty()) o.block[0] = base;
    for (size_t k = 1; k < o.block.size(); ++k) o.block[k] += o.block[k - 1];
    MPI_Allreduce(&total, &o.bonds, 1, MPI_INT64_T, MPI_SUM, comm_);
    // The answers: each received row's first place, back in the order it came.
    std::vector<int64_t> first(recv.size() / 2), back(owned);
    for (size_t k = 0; k < first.size(); ++k) first[k] = o.block[static_cast<size_t>(recv[2 * k] - o.block_first)];
    MPI_Alltoallv(first.data(), exchange.recv_counts.data(), exchange.recv_displs.data(), MPI_INT64_T, back.data(),
                  send_counts.data(), exchange.send_displs.data(), MPI_INT64_T, comm_);
    o.row_first.resize(owned);
    std::fill(at.begin(), at.end(), 0);  // the same walk as the sending one: row k's answer
    for (int q = 1; q < ranks; ++q) at[q] = at[q - 1] + send_counts[q - 1];
    for (size_t k = 0; k < owned; ++k) o.row_first[k] = back[static_cast<size_t>(at[rows.holding(local_.original_index[k])]++)];
    return o;
  }

  // Every rank writes its own rows of checkpoint.h5 (collective I/O): nothing is gathered.
  // The rows are the gathered file's (internal order: rank r's particles and its rows' bond
  // entries are one contiguous range of each array), so the file is the same.
  void checkpoint(PdSystem& g, const std::string& path, bool root, bool downloaded) override {
    if (!downloaded) to_host();
    const int64_t first = layout_.begin(), owned = layout_.owned();
    std::vector<int64_t> facets(static_cast<size_t>(layout_.part.ranks()) + 1, 0);  // without a gas load: none
    if (share_->gas) facets = share_->gas->facet_begin();
    const CheckpointRows mine{&local_,
                              static_cast<size_t>(first),
                              static_cast<size_t>(owned),
                              static_cast<size_t>(entry_ranges(layout_.part, g)[layout_.rank]),
                              static_cast<size_t>(local_.offsets[owned]),
                              static_cast<size_t>(facets[layout_.rank]),
                              static_cast<size_t>(facets[layout_.rank + 1] - facets[layout_.rank])};
    write_checkpoint(g, path, mine, comm_, root);
  }
#endif

  // results.h5's particles and bond list when a run (time loop or dynamic relaxation) starts:
  // with parallel HDF5 written by the ranks together and a restart's file checked by them
  // together (results_particles, results_bonds); else rank 0 wrote the particles, holds the
  // list and checks a restart's file alone (an error there reaches every rank through
  // mpi_abort_all). Collective; outside the parallel-HDF5 block above, since both builds call
  // it (relax, mpi_time_loop).
  void start_results(PdSystem& g, ResultsWriter* results, const std::string& out_dir) {
#ifdef BRECCIA_PARALLEL_HDF5
    results_particles(g, results, out_dir);
    results_bonds(g, results, out_dir);
#else
    (void)g;
    (void)out_dir;
    if (results) results->check_bond_count(results->bond_list_size());
#endif
  }

  // The probes and the indenter are read on their ranks (history_particles): nothing to gather.
  void download_kinematics(PdSystem&) override {}

  // The probes' values and the indenter's reaction, for rank 0's history line: each probe's
  // owner sends its particle's displacement or velocity, each rank its particles' indenter
  // terms in contact (indenter_terms, in index order; the ranks' in rank order, which is index
  // order), which rank 0 adds as one process does (indenter_reaction). Collective.
  std::optional<HistoryParticles> history_particles(PdSystem& g) override {
    const CaseConfig& c = g.config;
    HistoryParticles out;
    if (c.probes.empty() && !c.indenter.enabled) return out;
    kinematics_to_host();
    const int64_t first = layout_.begin(), owned = layout_.owned();
    if (!c.probes.empty()) {
      const std::vector<int64_t>& at = probe_particles(g);
      std::vector<double> mine;  // per owned probe: its number, then its 3 values
      for (size_t p = 0; p < at.size(); ++p) {
        if (at[p] < first || at[p] >= first + owned) continue;
        const std::vector<double>& src = c.probes[p].field == "velocity" ? local_.v : local_.u;
        mine.push_back(static_cast<double>(p));
        for (int d = 0; d < 3; ++d) mine.push_back(src[3 * static_cast<size_t>(at[p] - first) + d]);
      }
      const std::vector<double> all = gather_to_root(mine);
      out.probes.assign(3 * at.size(), 0.0);
      for (size_t k = 0; k + 3 < all.size(); k += 4)
        std::copy(all.begin() + static_cast<std::ptrdiff_t>(k + 1), all.begin() + static_cast<std::ptrdiff_t>(k + 4),
                  out.probes.begin() + 3 * static_cast<std::ptrdiff_t>(all[k]));
    }
    if (c.indenter.enabled) {
      const std::vector<IndenterTerm> mine = indenter_terms(local_, static_cast<size_t>(owned), first);
      indenter_reaction(gather_to_root(mine), out.indenter);
    }
    return out;
  }

  // The blow-up test of instability_message with its sums over the ranks: the energies are
  // (measure), correspondence's non-affine energy is summed here. Collective.
  bool unstable(PdSystem& g, const Energies& e, double energy_scale, bool root) override {
    const std::optional<double> nonaffine = nonaffine_over_ranks(g);  // every rank: a sum over them
    return any(root && instability_kind(g, e, energy_scale, nonaffine) != Instability::None);
  }

  // The message of a blow-up, naming the particle as one process does: the fastest (or the one
  // of largest non-affine energy) is the first of the largest over the ranks, the non-finite
  // one measure's; its owner sends rank 0 its file index and position. Collective.
  std::string instability(PdSystem& g, const Energies& e, double energy_scale) override {
    to_host();
    const std::optional<double> nonaffine = nonaffine_over_ranks(g);
    int kind = static_cast<int>(instability_kind(g, e, energy_scale, nonaffine));
    MPI_Bcast(&kind, 1, MPI_INT, 0, comm_);  // rank 0's judgement (every rank's energies are alike)
    const int64_t first = layout_.begin();
    const size_t owned = static_cast<size_t>(layout_.owned());
    int64_t pick = 0;
    if (kind == static_cast<int>(Instability::NonFinite)) {
      pick = e.bad_particle >= 0 ? e.bad_particle : 0;
    } else if (kind == static_cast<int>(Instability::ZeroEnergyModes)) {
      const auto [value, i] = first_largest(local_.corr_nonaffine, owned);
      pick = first_largest_over_ranks(value, first + i);
    } else if (kind == static_cast<int>(Instability::EnergyGrowth)) {
      const auto [speed2, i] = first_fastest(local_.v, owned);
      pick = first_largest_over_ranks(speed2, first + i);
    } else {
      return "";
    }
    // The particle's owner sends its file index (exact as a double) and reference position.
    const std::vector<int64_t>& begin = layout_.part.begin;
    const int owner = static_cast<int>(std::upper_bound(begin.begin(), begin.end(), pick) - begin.begin()) - 1;
    double named[4] = {0.0, 0.0, 0.0, 0.0};
    if (owner == layout_.rank) {
      const size_t k = static_cast<size_t>(pick - first);
      named[0] = static_cast<double>(local_.original_index[k]);
      for (int d = 0; d < 3; ++d) named[1 + d] = local_.x0[3 * k + d];
      if (owner != 0) MPI_Send(named, 4, MPI_DOUBLE, 0, kNamedTag, comm_);
    } else if (layout_.rank == 0) {
      MPI_Recv(named, 4, MPI_DOUBLE, owner, kNamedTag, comm_, MPI_STATUS_IGNORE);
    }
    NamedParticle where;
    where.file_index = static_cast<int64_t>(named[0]);
    std::copy(named + 1, named + 4, where.x0);
    return instability_text(g, e, energy_scale, static_cast<Instability>(kind), nonaffine.value_or(0.0), where);
  }

  // Dynamic relaxation on the rank's share: the force pass exchanges the halo, the sums
  // (load norm, residual, the damping's Rayleigh quotient) are taken over ranks,
  // reproducibly (reproducible_sum.hpp), so every rank and one process take the same
  // decisions from the same bits; then the history line (its particles from their owners:
  // history_particles) and the one output group written as the time loop's are: with parallel
  // HDF5 by every rank together (write_output; nothing gathered), else by rank 0's writer from
  // its staging (download).
  std::pair<long long, Energies> relax(PdSystem& g, const RunOptions& o, ResultsWriter* results,
                                       HistoryWriter* history) {
    start_results(g, results, o.out_dir);  // as the time loop's
    RelaxHooks hooks;
    hooks.forces = [this](PdSystem& l) {
      l.diagnostics = true;
      // ADR commits the minimum stretches itself (commit_min_stretch): the ghosts' follow.
      if (!l.min_stretch.empty()) halo_->exchange({{l.min_stretch.data(), sizeof(float)}});
      if (l.f32.active) float32_upload(l);  // ADR moves the double state
      force_pass(l);
      if (l.f32.active) float32_download(l);
    };
    // The gas's pressure follows the cavity's volume: its sums over every rank in one
    // process's order, its crack pass reading the ghosts (MpiExec), not the rank's share alone.
    hooks.external = [this](PdSystem& l, double t) {
      MpiExec exec(l, *halo_, share_->contact.get(), share_->gas.get());
      StepArrays<double> a = cpu_step_arrays(l);  // double, as compute_external's (float32 too)
      a.ghosts = layout_.ghosts();
      pd_external(exec, a, l, t);
    };
    hooks.sum = [this](double* values, int count) {
      MPI_Allreduce(MPI_IN_PLACE, values, count, MPI_DOUBLE, MPI_SUM, comm_);
    };
    hooks.max = [this](double* values, int count) {
      MPI_Allreduce(MPI_IN_PLACE, values, count, MPI_DOUBLE, MPI_MAX, comm_);
    };
    const long long iterations = relax_to_equilibrium(local_, o.progress, hooks);
    const Energies e = measure(g);  // and the accumulators
    download(g);
    g.step = local_.step;
    if (local_.gas.active) g.gas.copy_scalars(local_.gas);  // the history's and summary's gas
    const std::optional<HistoryParticles> particles = history_particles(g);
    if (history) history->write(g, e, &*particles);
#ifdef BRECCIA_PARALLEL_HDF5
    if (g.config.write_results) write_output(g, results, o.out_dir);
#else
    if (results) results->write(g);
#endif
    return {iterations, e};
  }

  bool any(bool flag) override {
    int mine = flag ? 1 : 0, all = 0;
    MPI_Allreduce(&mine, &all, 1, MPI_INT, MPI_MAX, comm_);
    return all != 0;
  }

private:
  // Whether rank 0 holds `global` (a gather's target): the other ranks let it go
  // (release_global_for_loop) but take part in the gather alike.
  template <class T, class A>
  bool held(const std::vector<T, A>& global) const {
    return !global.empty() ||
           std::find(released_.begin(), released_.end(), static_cast<const void*>(&global)) != released_.end();
  }
  template <class T, class A>
  void gather(const std::vector<T, A>& local, std::vector<T, A>& global, const std::vector<int64_t>& begin) {
    gather_ranges(local, global, begin, layout_.rank, comm_, held(global));
  }

  // The particles the probes read (global internal indices), found once: each rank's nearest
  // owned particle (nearest_particle), then the smallest (distance, index) over the ranks, the
  // particle one process's search finds (the first of the nearest). Collective.
  const std::vector<int64_t>& probe_particles(const PdSystem& g) {
    if (probe_particles_.size() == g.config.probes.size()) return probe_particles_;
    for (const ProbeSpec& p : g.config.probes) {
      const auto [d2, k] = nearest_particle(local_.x0.data(), static_cast<size_t>(layout_.owned()), p.position);
      // The nearest is the first largest of -d2 (negation is exact; ties: the smallest index).
      probe_particles_.push_back(first_largest_over_ranks(-d2, layout_.begin() + static_cast<int64_t>(k)));
    }
    return probe_particles_;
  }

  // The global index of the largest `value` over the ranks (each rank's first largest owned
  // one, at `index`), the smallest index among equal values: one process's first largest.
  int64_t first_largest_over_ranks(double value, int64_t index) {
    struct Candidate {
      double value;
      long long index;
    };
    int ranks = 1;
    MPI_Comm_size(comm_, &ranks);
    std::vector<Candidate> all(static_cast<size_t>(ranks));
    const Candidate mine{value, static_cast<long long>(index)};
    MPI_Allgather(&mine, sizeof mine, MPI_BYTE, all.data(), sizeof mine, MPI_BYTE, comm_);
    Candidate best = all[0];
    for (const Candidate& c : all)  // ascending ranks: ascending indices
      if (c.value > best.value) best = c;
    return best.index;
  }

  // Correspondence's non-affine energy (nonaffine_energy) summed over the ranks' own particles;
  // none for the other models. Collective.
  std::optional<double> nonaffine_over_ranks(const PdSystem& g) {
    if (g.config.model != PdModel::Correspondence) return std::nullopt;
    if (device_) to_host();  // the fields of the last pass
    double sum = local_.corr_nonaffine.empty() ? 0.0 : nonaffine_energy(local_);
    MPI_Allreduce(MPI_IN_PLACE, &sum, 1, MPI_DOUBLE, MPI_SUM, comm_);
    return sum;
  }

  // Every rank's `mine` to rank 0, in rank order (elements of T as bytes); empty elsewhere.
  template <class T>
  std::vector<T> gather_to_root(const std::vector<T>& mine) {
    int ranks = 1;
    MPI_Comm_size(comm_, &ranks);
    const int count = static_cast<int>(mine.size());
    std::vector<int> counts(static_cast<size_t>(ranks)), displs(static_cast<size_t>(ranks) + 1, 0);
    MPI_Gather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, comm_);
    for (int q = 0; q < ranks; ++q) displs[q + 1] = displs[q] + counts[q];
    std::vector<T> all(layout_.rank == 0 ? static_cast<size_t>(displs[ranks]) : 0);
    MPI_Datatype type;
    MPI_Type_contiguous(static_cast<int>(sizeof(T)), MPI_BYTE, &type);
    MPI_Type_commit(&type);
    MPI_Gatherv(mine.data(), count, type, all.data(), counts.data(), displs.data(), type, 0, comm_);
    MPI_Type_free(&type);
    return all;
  }

  // u and v of the rank's state into its host system (from the GPU, or float32's float state).
  void kinematics_to_host() {
    if (device_) device_->download_kinematics(local_);
    else if (local_.f32.active) float32_download_kinematics(local_);
  }
  // ... and gathered into rank 0's u and v where it holds them (serial HDF5's staging).
  void gather_kinematics(PdSystem& g) {
    const std::vector<int64_t> three = particle_ranges(layout_.part, 3);
    gather(local_.u, g.u, three);
    gather(local_.v, g.v, three);
  }

  // The rank's whole state into its host system (from the GPU, or float32's float state).
  void to_host() {
    if (device_) device_->download(local_);
    else if (local_.f32.active) float32_download(local_);
  }

  // The step's arrays over the rank's state in its precision, with the ghosts counted.
  template <class F>
  void with_step_arrays(PdSystem& l, F&& f) {
    if (l.f32.active) {
      StepArrays<float> a = float32_step_arrays(l);
      a.ghosts = layout_.ghosts();
      f(a);
    } else {
      StepArrays<double> a = cpu_step_arrays(l);
      a.ghosts = layout_.ghosts();
      f(a);
    }
  }

  void force_pass(PdSystem& l) {
    MpiExec exec(l, *halo_, share_->contact.get(), share_->gas.get());
    with_step_arrays(l, [&](auto& a) { pd_force_pass(exec, a, true); });
  }

  MPI_Comm comm_;
  std::shared_ptr<RankShare> share_;
  const RankLayout& layout_ = share_->layout;
  PdSystem& local_ = share_->local;
  std::unique_ptr<HaloExchange>& halo_ = share_->halo;
  std::unique_ptr<StepBackend> device_;  // --backend cuda: the rank's system on its GPU
  std::vector<const void*> released_;    // the global arrays this rank let go of (held())
#ifdef BRECCIA_PARALLEL_HDF5
  FileBondOffsets file_bond_offsets_;  // file_bond_offsets: once
  int64_t broken_bits_held_ = 0;       // the most bytes of broken bits held (broken_bits_together)
#endif
  std::vector<int64_t> probe_particles_;    // probe_particles: once
  static constexpr int kNamedTag = 7103;    // instability: the named particle's owner to rank 0
};

}  // namespace

std::unique_ptr<StepBackend> make_mpi_backend(PdSystem& global, MPI_Comm comm, bool cuda) {
  return std::make_unique<MpiBackend>(global, comm, cuda);
}

namespace {
// One force pass of the stable-step estimate on the rank's system, with the global system's
// switches (the estimate turns fracture and diagnostics off in it): the ghosts' displacements
// from their owners first, then the owned rows' forces.
void rank_force_pass(RankShare& sh, const PdSystem& g) {
  PdSystem& l = sh.local;
  l.config.fracture = g.config.fracture;
  l.diagnostics = g.diagnostics;
  MpiExec exec(l, *sh.halo, sh.contact.get(), sh.gas.get());
  StepArrays<double> a = cpu_step_arrays(l);
  a.ghosts = sh.layout.ghosts();
  pd_force_pass(exec, a, true);
}
}  // namespace

ForcePass mpi_stable_step_forces(PdSystem& global) {
  int size = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  if (size == 1) return {};
  // The rank's system, built here once and kept for the time loop's backend.
  // A distributed set-up's bonds move into the rank's system: the global one lets them go.
  auto sh = make_rank_share(global, MPI_COMM_WORLD, global.distributed_rows.empty() ? nullptr : &global);
  g_setup_share = sh;
  // The displacements and velocities are in the rank's system now: a distributed set-up's
  // ranks other than 0 let the global ones go here, before the estimate's peak (48 B per
  // particle). The loop's backend keeps the rank's (copy_rank_state); the pass below, which
  // ends the estimate at the set-up's displacement, takes the rank's rows of it from `u0`
  // (the estimate's iterations write their probes to the rank's system's u).
  // So do the forces and the fields the pass below fills (kForcePassFields: 72 B per particle
  // on PMB, more with LPS's factors and correspondence's tensors): the pass leaves the owned
  // values in the rank's system, the ghosts' come from their owners (the halo exchange), and
  // only a staged rank 0 (serial HDF5), whose writers read them, gathers them whole; LPS's weighted volume, which
  // the rank's system took at its cut and no one reads in the global system after it; and a
  // gas load's per-particle arrays. The cut itself lets each go as soon as it has taken the
  // rank's rows of it (restrict_to_rank_taking_bonds: the cut's growth was the estimate's peak).
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  const bool distributed = !global.distributed_rows.empty();
  std::vector<double> u0;
  const bool staged = rank == 0 && root_stages_whole_body();  // its writers read the whole fields
  if (!staged && distributed) {
    u0 = sh->local.u;
    release_global_at_stable_step(global);  // the cut took and let go of most already (take_releasing)
#if defined(__GLIBC__)
    malloc_trim(0);  // what the cut left of the whole arrays back to the system, before the Lanczos vectors
#endif
  }
  // The whole-system set-up's ranks compute their rows at the global system's displacement
  // and all gather the forces: every rank then holds one process's force array, bit for bit
  // (the power iteration, estimate_max_frequency, which the set-up does not call, takes every
  // pass here, on a whole system's u). The set-up's Lanczos estimate runs its iterations on
  // the ranks' shares instead (mpi_stable_step_ranks: no vector whole on any rank) and calls
  // this pass once, at the real displacement, at its end.
  return [sh, u0 = std::move(u0), staged](PdSystem& g) {
    PdSystem& l = sh->local;
    const RankLayout& L = sh->layout;
    const int64_t b = L.begin(), owned = L.owned();
    if (g.u.empty()) {  // let go above: the set-up's displacements of the rank's particles
      if (u0.size() != l.u.size()) throw std::logic_error("stable step: the rank's displacements");
      std::copy(u0.begin(), u0.end(), l.u.begin());
    } else {
      std::copy(g.u.begin() + 3 * b, g.u.begin() + 3 * (b + owned), l.u.begin());
      for (int64_t q = 0; q < L.ghosts(); ++q)
        std::copy_n(g.u.begin() + 3 * static_cast<int64_t>(L.halo.ghosts[q]), 3, l.u.begin() + 3 * (owned + q));
    }
    rank_force_pass(*sh, g);
    if (g.distributed_rows.empty()) {
      std::copy(l.force.begin(), l.force.begin() + 3 * owned, g.force.begin() + 3 * b);
      allgather_ranges(g.force.data(), sizeof(double), particle_ranges(L.part, 3), MPI_COMM_WORLD);
      return;
    }
    // The global system holds no bonds to run the pass that ends the estimate (at the real
    // displacement, fracture on): the rank's system keeps what it computed, its ghosts taking
    // their owners' values (what the rank's system took from the whole arrays before), and a
    // staged rank 0 (root_stages_whole_body: serial HDF5) gathers every rank's owned values
    // whole, for its writers (the first output, the first history line) and the start of its
    // own system; with parallel HDF5 the ranks write their own rows and no rank gathers. Correspondence's deformation
    // gradient, force tensor and non-affine energy too (9, 9 and 1 per particle): the owned
    // values the first output's zero-energy check and the ranks' systems start from, as the
    // whole system's pass leaves them on one process. Every rank holds the same fields (the
    // case decides which): the same exchanges and gathers on every rank.
    auto share = [&](std::vector<double>& local, std::vector<double>& whole, size_t width) {
      if (local.empty()) return;  // the model has none (every rank alike)
      sh->halo->exchange({{local.data(), width * sizeof(double)}});
      if (!root_stages_whole_body()) return;  // (parallel HDF5: the ranks write their own rows)
      if (staged && whole.size() != width * g.n) throw std::logic_error("stable step: rank 0's whole " + std::to_string(width) + "-wide field");
      gather_ranges(local, whole, particle_ranges(L.part, width), L.rank, MPI_COMM_WORLD, true);
    };
    share(l.force, g.force, 3);
    for (const auto& [field, width] : kForcePassFields) share(l.*field, g.*field, static_cast<size_t>(width));
    std::copy(l.state.begin(), l.state.end(), g.state.begin());
    std::copy(l.bond_damage.begin(), l.bond_damage.end(), g.bond_damage.begin());  // softening bonds
    g.dissipated_energy = l.dissipated_energy;
  };
}

StableStepRanks mpi_stable_step_ranks() {
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  std::shared_ptr<RankShare> sh = g_setup_share;  // mpi_stable_step_forces's, just built
  if (size == 1 || !sh) return {};
  StableStepRanks r;
  r.begin = sh->layout.begin();
  r.end = r.begin + sh->layout.owned();
  r.particles = static_cast<int64_t>(sh->body_n);
  r.u = sh->local.u.data();
  r.force = sh->local.force.data();
  r.system = &sh->local;
  r.pass = [sh](PdSystem& g) { rank_force_pass(*sh, g); };
  // Rank r continues rank r - 1's running sum over its own terms and hands it on; the last
  // rank's is the sum, one process's bits (its loop term by term), sent to every rank.
  r.chain = [rank, size](const std::function<double(double)>& f) {
    double sum = 0.0;
    if (rank > 0) MPI_Recv(&sum, 1, MPI_DOUBLE, rank - 1, 0, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    sum = f(sum);
    if (rank + 1 < size) MPI_Send(&sum, 1, MPI_DOUBLE, rank + 1, 0, MPI_COMM_WORLD);
    MPI_Bcast(&sum, 1, MPI_DOUBLE, size - 1, MPI_COMM_WORLD);
    return sum;
  };
  return r;
}

DistributedSetup mpi_distributed_setup() {
  DistributedSetup d;
  MPI_Comm_rank(MPI_COMM_WORLD, &d.rank);
  MPI_Comm_size(MPI_COMM_WORLD, &d.ranks);
  d.concat = [](const void* data, size_t count, size_t element_bytes, bool everyone) {
    int rank = 0, ranks = 1;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &ranks);
    long long mine = static_cast<long long>(count);
    std::vector<long long> counts(static_cast<size_t>(ranks));
    MPI_Allgather(&mine, 1, MPI_LONG_LONG, counts.data(), 1, MPI_LONG_LONG, MPI_COMM_WORLD);
    std::vector<int64_t> begin(static_cast<size_t>(ranks) + 1, 0);
    for (int r = 0; r < ranks; ++r) begin[r + 1] = begin[r] + counts[r];
    const ElementRanges e(element_bytes, begin);
    std::vector<char> out;
    if (everyone || rank == 0) out.resize(static_cast<size_t>(begin[ranks]) * element_bytes);
    if (everyone)
      MPI_Allgatherv(data, static_cast<int>(count), e.type, out.data(), e.counts.data(), e.displs.data(), e.type,
                     MPI_COMM_WORLD);
    else
      MPI_Gatherv(data, static_cast<int>(count), e.type, out.data(), e.counts.data(), e.displs.data(), e.type, 0,
                  MPI_COMM_WORLD);
    return out;
  };
  d.exchange = [](const void* data, const std::vector<int64_t>& counts, size_t element_bytes,
                  std::vector<int64_t>& received) {
    int ranks = 1;
    MPI_Comm_size(MPI_COMM_WORLD, &ranks);
    if (counts.size() != static_cast<size_t>(ranks)) throw std::logic_error("distributed set-up: an exchange's counts");
    std::vector<long long> send(counts.begin(), counts.end()), recv(static_cast<size_t>(ranks));
    MPI_Alltoall(send.data(), 1, MPI_LONG_LONG, recv.data(), 1, MPI_LONG_LONG, MPI_COMM_WORLD);
    received.assign(recv.begin(), recv.end());
    std::vector<int64_t> send_begin(static_cast<size_t>(ranks) + 1, 0), recv_begin(static_cast<size_t>(ranks) + 1, 0);
    for (int r = 0; r < ranks; ++r) {
      send_begin[r + 1] = send_begin[r] + send[r];
      recv_begin[r + 1] = recv_begin[r] + recv[r];
    }
    // Elements of element_bytes each (ElementRanges: displacements in elements, not bytes).
    const ElementRanges sent(element_bytes, send_begin), arriving(element_bytes, recv_begin);
    std::vector<char> out(static_cast<size_t>(recv_begin[ranks]) * element_bytes);
    MPI_Alltoallv(data, sent.counts.data(), sent.displs.data(), sent.type, out.data(), arriving.counts.data(),
                  arriving.displs.data(), arriving.type, MPI_COMM_WORLD);
    return out;
  };
  return d;
}

std::pair<long long, Energies> mpi_relax(PdSystem& global, const RunOptions& o, ResultsWriter* results,
                                         HistoryWriter* history) {
  MpiBackend backend(global, MPI_COMM_WORLD);
  try {
    return backend.relax(global, o, results, history);
  } catch (const std::exception& e) {
    mpi_abort_all(e.what(), kExitRunFailed);
  }
}

RunResult mpi_time_loop(PdSystem& global, const RunOptions& o, ResultsWriter* results, HistoryWriter* history) {
  // Every rank gets here with the same (replicated) system, so a case the backend refuses is
  // refused by all alike: an InputError, reported once by rank 0.
  const bool cuda = o.backend == "cuda";
  const auto backend = std::make_unique<MpiBackend>(global, MPI_COMM_WORLD, cuda);
  try {
    if (cuda) print_rank_devices(MPI_COMM_WORLD, o.progress);
    backend->start_results(global, results, o.out_dir);
    RunResult r = run_time_loop(global, o, *backend, results, history);
    // Every rank's resident set at the end of its loop, to rank 0 (summary.json).
    double mine = r.loop_resident_mb.empty() ? -1.0 : r.loop_resident_mb[0];
    int rank = 0, ranks = 1;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &ranks);
    std::vector<double> all(static_cast<size_t>(ranks));
    MPI_Gather(&mine, 1, MPI_DOUBLE, all.data(), 1, MPI_DOUBLE, 0, MPI_COMM_WORLD);
    if (std::find(all.begin(), all.end(), -1.0) == all.end()) r.loop_resident_mb = all;
    else r.loop_resident_mb.clear();
    if (rank == 0) r.loop_whole_bytes_rank0 = static_cast<long long>(loop_state_bytes(global));
    return r;
  } catch (const std::exception& e) {
    // From here a failure may be one rank's alone (a file rank 0 writes): stop them all.
    mpi_abort_all(e.what(), dynamic_cast<const InputError*>(&e) ? kExitBadInput : kExitRunFailed);
  }
}

}  // namespace breccia::solver
