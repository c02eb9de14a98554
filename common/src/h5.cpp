#include "breccia/common/h5.hpp"

#include <stdexcept>
#include <type_traits>

#include "breccia/common/error.hpp"

namespace breccia::h5 {
namespace {

// Silence HDF5's own stack printing: we turn failures into our own messages.
struct QuietErrors {
  QuietErrors() { H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr); }
};
const QuietErrors quiet;

struct Handle {
  hid_t id;
  herr_t (*close)(hid_t);
  ~Handle() { if (id >= 0) close(id); }
};

template <class T> hid_t mem_type();
template <> hid_t mem_type<double>() { return H5T_NATIVE_DOUBLE; }
template <> hid_t mem_type<float>() { return H5T_NATIVE_FLOAT; }
template <> hid_t mem_type<int64_t>() { return H5T_NATIVE_INT64; }
template <> hid_t mem_type<int32_t>() { return H5T_NATIVE_INT32; }
template <> hid_t mem_type<uint8_t>() { return H5T_NATIVE_UINT8; }

std::string parent_of(const std::string& p) {
  const auto pos = p.find_last_of('/');
  if (pos == std::string::npos || pos == 0) return "/";
  return p.substr(0, pos);
}

}  // namespace

File::File(const std::string& path, Mode mode) : path_(path) {
  switch (mode) {
    case Mode::Read: id_ = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT); break;
    case Mode::ReadWrite: id_ = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT); break;
    case Mode::Create: id_ = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT); break;
  }
  if (id_ < 0) {
    if (mode == Mode::Create) throw RunError("cannot create HDF5 file " + path);
    throw InputError(path, "", "cannot be opened as an HDF5 file", "an HDF5 file written by Breccia");
  }
}

#ifdef BRECCIA_PARALLEL_HDF5
File::File(const std::string& path, Mode mode, MPI_Comm comm) : path_(path) {
  Handle access{H5Pcreate(H5P_FILE_ACCESS), H5Pclose};
  H5Pset_fapl_mpio(access.id, comm, MPI_INFO_NULL);
  switch (mode) {
    case Mode::Read: id_ = H5Fopen(path.c_str(), H5F_ACC_RDONLY, access.id); break;
    case Mode::ReadWrite: id_ = H5Fopen(path.c_str(), H5F_ACC_RDWR, access.id); break;
    case Mode::Create: id_ = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, access.id); break;
  }
  if (id_ < 0) {
    if (mode == Mode::Create) throw RunError("cannot create HDF5 file " + path + " (collectively, MPI-IO)");
    throw InputError(path, "", "cannot be opened as an HDF5 file", "an HDF5 file written by Breccia");
  }
  transfer_ = H5Pcreate(H5P_DATASET_XFER);
  H5Pset_dxpl_mpio(transfer_, H5FD_MPIO_COLLECTIVE);
}
#endif

File::~File() {
  if (transfer_ >= 0) H5Pclose(transfer_);
  if (id_ >= 0) H5Fclose(id_);
}

void File::flush() const { H5Fflush(id_, H5F_SCOPE_GLOBAL); }

bool File::exists(const std::string& object_path) const {
  // H5Lexists must be checked level by level.
  std::string prefix;
  size_t start = 1;
  while (start <= object_path.size()) {
    const size_t next = object_path.find('/', start);
    prefix = object_path.substr(0, next == std::string::npos ? object_path.size() : next);
    if (H5Lexists(id_, prefix.c_str(), H5P_DEFAULT) <= 0) return false;
    if (next == std::string::npos) break;
    start = next + 1;
  }
  return true;
}

void File::create_group(const std::string& group_path) const {
  if (group_path == "/" || exists(group_path)) return;
  create_group(parent_of(group_path));
  Handle g{H5Gcreate2(id_, group_path.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose};
  if (g.id < 0) throw RunError(path_ + ": cannot create group " + group_path);
}

std::vector<std::string> File::children(const std::string& group_path) const {
  std::vector<std::string> names;
  if (!exists(group_path) && group_path != "/") return names;
  Handle g{H5Gopen2(id_, group_path.c_str(), H5P_DEFAULT), H5Gclose};
  if (g.id < 0) return names;
  H5G_info_t info;
  // A damaged file can open the group and fail to list it: bad input naming the group, not a
  // name of length -1.
  if (H5Gget_info(g.id, &info) < 0) throw InputError(path_, group_path, "its members cannot be listed", "a readable group");
  for (hsize_t i = 0; i < info.nlinks; ++i) {
    const ssize_t len = H5Lget_name_by_idx(g.id, ".", H5_INDEX_NAME, H5_ITER_INC, i, nullptr, 0, H5P_DEFAULT);
    if (len < 0) throw InputError(path_, group_path, "member " + std::to_string(i) + "'s name cannot be read", "a readable group");
    std::string name(static_cast<size_t>(len), '\0');
    H5Lget_name_by_idx(g.id, ".", H5_INDEX_NAME, H5_ITER_INC, i, name.data(), len + 1, H5P_DEFAULT);
    names.push_back(name);
  }
  return names;
}

// The union of runs [lo, hi) (none empty) of rows of a dataspace of shape dims, as a new
// dataspace (the caller closes it): halves merged pairwise (H5Scombine_select), since OR-ing
// one run at a time into one selection takes time quadratic in the runs (HDF5 1.10.8 merges
// the whole span list each time: 10,000 runs 2.3 s, against 0.01 s so; 100,000 runs 0.14 s).
static hid_t select_runs(hid_t space, const std::vector<RowRun>& runs, size_t lo, size_t hi,
                         const std::vector<hsize_t>& dims) {
  if (hi - lo <= 32) {
    const hid_t s = H5Scopy(space);
    H5Sselect_none(s);
    std::vector<hsize_t> start(dims.size(), 0), block(dims);
    for (size_t q = lo; q < hi; ++q) {
      start[0] = runs[q].first;
      block[0] = runs[q].rows;
      H5Sselect_hyperslab(s, H5S_SELECT_OR, start.data(), nullptr, block.data(), nullptr);
    }
    return s;
  }
  const size_t mid = lo + (hi - lo) / 2;
  const Handle a{select_runs(space, runs, lo, mid, dims), H5Sclose}, b{select_runs(space, runs, mid, hi, dims), H5Sclose};
  return H5Scombine_select(a.id, H5S_SELECT_OR, b.id);
}

// Runs of rows (first row, rows; ascending, disjoint) of a dataset of shape dims, from data (the
// runs' rows one after another); every row when one process writes it (transfer < 0: one run
// of every row), else each process of a collective file its own runs (transfer: the
// collective transfer list; a process with no rows selects none and still takes part).
template <class T>
static void write_impl(const File& f, const std::string& path, const T* data, const std::vector<RowRun>& runs,
                       std::vector<hsize_t> dims, hid_t transfer, Filter filter = Filter::Deflate) {
  hsize_t total = 1;
  for (auto d : dims) total *= d;
  hsize_t rows = 0, end = 0;
  bool inside = !dims.empty();
  for (const RowRun& r : runs) {
    inside = inside && r.first >= end && r.first <= dims[0] && r.rows <= dims[0] - r.first;
    end = r.first + r.rows;
    rows += r.rows;
  }
  if (!inside || (transfer < 0 && (runs.size() != 1 || rows != dims[0])))
    throw std::logic_error("h5 write " + path + ": rows outside the dataset's");
  f.create_group(parent_of(path));
  if (f.exists(path)) H5Ldelete(f.id(), path.c_str(), H5P_DEFAULT);
  Handle space{H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr), H5Sclose};
  Handle plist{H5Pcreate(H5P_DATASET_CREATE), H5Pclose};
  // Chunk + deflate big arrays: particle files of 10^6+ particles shrink a lot.
  if (total > 65536) {
    std::vector<hsize_t> chunk = dims;
    chunk[0] = std::min<hsize_t>(dims[0], 65536);
    H5Pset_chunk(plist.id, static_cast<int>(chunk.size()), chunk.data());
    if (filter == Filter::ScaleOffset) {
      if constexpr (!std::is_integral_v<T>) throw std::logic_error("h5 write " + path + ": scale-offset is for integers");
      H5Pset_scaleoffset(plist.id, H5Z_SO_INT, H5Z_SO_INT_MINBITS_DEFAULT);
    } else {
      H5Pset_deflate(plist.id, 1);
    }
  }
  Handle ds{H5Dcreate2(f.id(), path.c_str(), mem_type<T>(), space.id, H5P_DEFAULT, plist.id, H5P_DEFAULT),
            H5Dclose};
  if (ds.id < 0) throw RunError(f.path() + ": cannot create dataset " + path);
  if (total == 0) return;
  herr_t written = 0;
  if (transfer < 0) {
    written = H5Dwrite(ds.id, mem_type<T>(), H5S_ALL, H5S_ALL, H5P_DEFAULT, data);
  } else {
    Handle whole{H5Dget_space(ds.id), H5Sclose};
    std::vector<RowRun> held;  // the runs with rows
    for (const RowRun& r : runs)
      if (r.rows > 0) held.push_back(r);
    std::vector<hsize_t> block(dims);
    block[0] = rows;
    hsize_t one = 1;
    Handle mem_space{rows > 0 ? H5Screate_simple(static_cast<int>(block.size()), block.data(), nullptr)
                              : H5Screate_simple(1, &one, nullptr),
                     H5Sclose};
    Handle file_space{held.empty() ? H5Scopy(whole.id) : select_runs(whole.id, held, 0, held.size(), dims), H5Sclose};
    if (held.empty()) {
      H5Sselect_none(file_space.id);
      H5Sselect_none(mem_space.id);
    }
    written = H5Dwrite(ds.id, mem_type<T>(), mem_space.id, file_space.id, transfer, data);
  }
  if (written < 0) throw RunError(f.path() + ": cannot write dataset " + path);
}

template <class T>
static void write_whole(const File& f, const std::string& path, const std::vector<T>& data, std::vector<hsize_t> dims,
                        hid_t transfer, Filter filter = Filter::Deflate) {
  hsize_t total = 1;
  for (auto d : dims) total *= d;
  if (total != data.size()) throw std::logic_error("h5 write " + path + ": dims do not match data size");
  // On a collective file every process writes the whole array, the same values.
  write_impl(f, path, data.data(), {{0, dims.empty() ? 0 : dims[0]}}, dims, transfer, filter);
}

void File::write(const std::string& p, const std::vector<double>& d, std::vector<hsize_t> dims) const {
  write_whole(*this, p, d, dims, transfer_);
}
void File::write(const std::string& p, const std::vector<float>& d, std::vector<hsize_t> dims) const {
  write_whole(*this, p, d, dims, transfer_);
}
void File::write(const std::string& p, const std::vector<int64_t>& d, std::vector<hsize_t> dims, Filter filter) const {
  write_whole(*this, p, d, dims, transfer_, filter);
}
void File::write(const std::string& p, const std::vector<int32_t>& d, std::vector<hsize_t> dims) const {
  write_whole(*this, p, d, dims, transfer_);
}
void File::write(const std::string& p, const std::vector<uint8_t>& d, std::vector<hsize_t> dims) const {
  write_whole(*this, p, d, dims, transfer_);
}

void File::write_rows(const std::string& p, const double* d, hsize_t first, hsize_t rows, std::vector<hsize_t> dims) const {
  write_impl(*this, p, d, {{first, rows}}, dims, transfer_);
}
void File::write_rows(const std::string& p, const float* d, hsize_t first, hsize_t rows, std::vector<hsize_t> dims) const {
  write_impl(*this, p, d, {{first, rows}}, dims, transfer_);
}
void File::write_rows(const std::string& p, const uint8_t* d, hsize_t first, hsize_t rows, std::vector<hsize_t> dims) const {
  write_impl(*this, p, d, {{first, rows}}, dims, transfer_);
}
void File::write_rows(const std::string& p, const int64_t* d, hsize_t first, hsize_t rows, std::vector<hsize_t> dims) const {
  write_impl(*this, p, d, {{first, rows}}, dims, transfer_);
}
void File::write_rows(const std::string& p, const int32_t* d, hsize_t first, hsize_t rows, std::vector<hsize_t> dims) const {
  write_impl(*this, p, d, {{first, rows}}, dims, transfer_);
}
void File::write_runs(const std::string& p, const int64_t* d, const std::vector<RowRun>& runs,
                      std::vector<hsize_t> dims, Filter filter) const {
  write_impl(*this, p, d, runs, dims, transfer_, filter);
}

void File::write_strings(const std::string& path, const std::vector<std::string>& values) const {
  create_group(parent_of(path));
  if (exists(path)) H5Ldelete(id_, path.c_str(), H5P_DEFAULT);
  Handle type{H5Tcopy(H5T_C_S1), H5Tclose};
  H5Tset_size(type.id, H5T_VARIABLE);
  hsize_t n = values.size();
  Handle space{H5Screate_simple(1, &n, nullptr), H5Sclose};
  Handle ds{H5Dcreate2(id_, path.c_str(), type.id, space.id, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Dclose};
  std::vector<const char*> ptrs;
  for (const auto& v : values) ptrs.push_back(v.c_str());
  if (n > 0 && H5Dwrite(ds.id, type.id, H5S_ALL, H5S_ALL, H5P_DEFAULT, ptrs.data()) < 0)
    throw RunError(path_ + ": cannot write " + path);
}

std::vector<hsize_t> File::dims(const std::string& path) const {
  if (!exists(path)) throw InputError(path_, path, "dataset is missing", "a dataset " + path);
  Handle ds{H5Dopen2(id_, path.c_str(), H5P_DEFAULT), H5Dclose};
  Handle space{H5Dget_space(ds.id), H5Sclose};
  const int rank = H5Sget_simple_extent_ndims(space.id);
  std::vector<hsize_t> d(static_cast<size_t>(std::max(rank, 0)));
  H5Sget_simple_extent_dims(space.id, d.data(), nullptr);
  return d;
}

template <class T>
static std::vector<T> read_impl(const File& f, const std::string& path) {
  const auto d = f.dims(path);
  hsize_t total = 1;
  for (auto x : d) total *= x;
  std::vector<T> out(total);
  Handle ds{H5Dopen2(f.id(), path.c_str(), H5P_DEFAULT), H5Dclose};
  if (total > 0 && H5Dread(ds.id, mem_type<T>(), H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()) < 0)
    throw InputError(f.path(), path, "cannot be read as a numeric dataset", "numeric data");
  return out;
}

template <class T>
static std::vector<T> read_runs_impl(const File& f, const std::string& path, const std::vector<RowRun>& runs,
                                     const char* expected = "a dataset with those rows (a file of this case)") {
  const std::vector<hsize_t> d = f.dims(path);
  hsize_t rows = 0, end = 0;
  std::vector<RowRun> held;  // the runs with rows
  for (const RowRun& r : runs) {
    if (d.empty() || r.first < end || r.first > d[0] || r.rows > d[0] - r.first)
      throw InputError(f.path(), path,
                       "has " + std::to_string(d.empty() ? 0 : d[0]) + " rows; rows " + std::to_string(r.first) +
                           " to " + std::to_string(r.first + r.rows) + " were asked for",
                       expected);
    end = r.first + r.rows;
    rows += r.rows;
    if (r.rows > 0) held.push_back(r);
  }
  hsize_t row = 1;
  for (size_t a = 1; a < d.size(); ++a) row *= d[a];
  std::vector<T> out(rows * row);
  if (out.empty()) return out;
  Handle ds{H5Dopen2(f.id(), path.c_str(), H5P_DEFAULT), H5Dclose};
  Handle whole{H5Dget_space(ds.id), H5Sclose};
  Handle file_space{select_runs(whole.id, held, 0, held.size(), d), H5Sclose};
  std::vector<hsize_t> block(d);
  block[0] = rows;
  Handle mem_space{H5Screate_simple(static_cast<int>(block.size()), block.data(), nullptr), H5Sclose};
  if (H5Dread(ds.id, mem_type<T>(), mem_space.id, file_space.id, H5P_DEFAULT, out.data()) < 0)
    throw InputError(f.path(), path, "cannot be read as a numeric dataset", "numeric data");
  return out;
}

// One run of rows (a particle file's, by the readers of a distributed set-up).
template <class T>
static std::vector<T> read_rows_impl(const File& f, const std::string& path, hsize_t first, hsize_t count) {
  return read_runs_impl<T>(f, path, {{first, count}}, "a dataset with those rows (a particle file of this case)");
}

std::vector<double> File::read_double_runs(const std::string& p, const std::vector<RowRun>& runs) const {
  return read_runs_impl<double>(*this, p, runs);
}
std::vector<double> File::read_doubles(const std::string& p) const { return read_impl<double>(*this, p); }
std::vector<float> File::read_floats(const std::string& p) const { return read_impl<float>(*this, p); }
std::vector<int64_t> File::read_int64(const std::string& p) const { return read_impl<int64_t>(*this, p); }
std::vector<int32_t> File::read_int32(const std::string& p) const { return read_impl<int32_t>(*this, p); }
std::vector<uint8_t> File::read_uint8(const std::string& p) const { return read_impl<uint8_t>(*this, p); }
std::vector<double> File::read_double_rows(const std::string& p, hsize_t first, hsize_t count) const {
  return read_rows_impl<double>(*this, p, first, count);
}
std::vector<int32_t> File::read_int32_rows(const std::string& p, hsize_t first, hsize_t count) const {
  return read_rows_impl<int32_t>(*this, p, first, count);
}
std::vector<int64_t> File::read_int64_rows(const std::string& p, hsize_t first, hsize_t count) const {
  return read_rows_impl<int64_t>(*this, p, first, count);
}
std::vector<uint8_t> File::read_uint8_rows(const std::string& p, hsize_t first, hsize_t count) const {
  return read_rows_impl<uint8_t>(*this, p, first, count);
}

std::vector<std::string> File::read_strings(const std::string& path) const {
  const auto d = dims(path);
  const hsize_t n = d.empty() ? 0 : d[0];
  Handle ds{H5Dopen2(id_, path.c_str(), H5P_DEFAULT), H5Dclose};
  Handle type{H5Tcopy(H5T_C_S1), H5Tclose};
  H5Tset_size(type.id, H5T_VARIABLE);
  std::vector<char*> ptrs(n, nullptr);
  if (n > 0 && H5Dread(ds.id, type.id, H5S_ALL, H5S_ALL, H5P_DEFAULT, ptrs.data()) < 0)
    throw InputError(path_, path, "cannot be read as strings", "a string dataset");
  std::vector<std::string> out;
  for (auto* p : ptrs) out.emplace_back(p ? p : "");
  if (n > 0) {
    Handle space{H5Dget_space(ds.id), H5Sclose};
    H5Dvlen_reclaim(type.id, space.id, H5P_DEFAULT, ptrs.data());
  }
  return out;
}

namespace {
Handle open_object(hid_t file, const std::string& obj) {
  return Handle{H5Oopen(file, obj.c_str(), H5P_DEFAULT), H5Oclose};
}
void replace_attr(hid_t obj, const std::string& name) {
  if (H5Aexists(obj, name.c_str()) > 0) H5Adelete(obj, name.c_str());
}
}  // namespace

void File::set_attr(const std::string& obj, const std::string& name, const std::string& value) const {
  Handle o = open_object(id_, obj);
  replace_attr(o.id, name);
  Handle type{H5Tcopy(H5T_C_S1), H5Tclose};
  H5Tset_size(type.id, std::max<size_t>(value.size(), 1));
  Handle space{H5Screate(H5S_SCALAR), H5Sclose};
  Handle a{H5Acreate2(o.id, name.c_str(), type.id, space.id, H5P_DEFAULT, H5P_DEFAULT), H5Aclose};
  std::string padded = value.empty() ? std::string(1, '\0') : value;
  H5Awrite(a.id, type.id, padded.data());
}

void File::set_attr(const std::string& obj, const std::string& name, double value) const {
  Handle o = open_object(id_, obj);
  replace_attr(o.id, name);
  Handle space{H5Screate(H5S_SCALAR), H5Sclose};
  Handle a{H5Acreate2(o.id, name.c_str(), H5T_NATIVE_DOUBLE, space.id, H5P_DEFAULT, H5P_DEFAULT), H5Aclose};
  H5Awrite(a.id, H5T_NATIVE_DOUBLE, &value);
}

void File::set_attr(const std::string& obj, const std::string& name, long long value) const {
  Handle o = open_object(id_, obj);
  replace_attr(o.id, name);
  Handle space{H5Screate(H5S_SCALAR), H5Sclose};
  Handle a{H5Acreate2(o.id, name.c_str(), H5T_NATIVE_LLONG, space.id, H5P_DEFAULT, H5P_DEFAULT), H5Aclose};
  H5Awrite(a.id, H5T_NATIVE_LLONG, &value);
}

bool File::has_attr(const std::string& obj, const std::string& name) const {
  if (obj != "/" && !exists(obj)) return false;
  Handle o = open_object(id_, obj);
  return H5Aexists(o.id, name.c_str()) > 0;
}

std::string File::attr_string(const std::string& obj, const std::string& name) const {
  if (!has_attr(obj, name)) throw InputError(path_, obj + "@" + name, "attribute is missing", "attribute " + name);
  Handle o = open_object(id_, obj);
  Handle a{H5Aopen(o.id, name.c_str(), H5P_DEFAULT), H5Aclose};
  // A damaged file can name the attribute and still not give it: each call is checked, so
  // that it is bad input naming the attribute, not a string of a garbage length.
  const auto unreadable = [&](const std::string& why) {
    return InputError(path_, obj + "@" + name, why, "a readable text attribute");
  };
  if (a.id < 0) throw unreadable("cannot be opened");
  Handle type{H5Aget_type(a.id), H5Tclose};
  if (type.id < 0 || H5Tget_class(type.id) != H5T_STRING) throw unreadable("is not text");
  if (H5Tis_variable_str(type.id) > 0) {  // as h5py writes a Python str
    Handle space{H5Aget_space(a.id), H5Sclose};
    if (space.id < 0 || H5Sget_simple_extent_npoints(space.id) != 1) throw unreadable("is not one text value");
    char* text = nullptr;
    if (H5Aread(a.id, type.id, &text) < 0) throw unreadable("cannot be read");
    std::string out = text ? text : "";
    H5free_memory(text);
    return out;
  }
  const size_t size = H5Tget_size(type.id);
  if (size == 0 || size > (size_t{1} << 20)) throw unreadable("text of " + std::to_string(size) + " bytes");
  std::string out(size, '\0');
  if (H5Aread(a.id, type.id, out.data()) < 0) throw unreadable("cannot be read");
  while (!out.empty() && out.back() == '\0') out.pop_back();
  return out;
}

double File::attr_double(const std::string& obj, const std::string& name) const {
  if (!has_attr(obj, name)) throw InputError(path_, obj + "@" + name, "attribute is missing", "attribute " + name);
  Handle o = open_object(id_, obj);
  Handle a{H5Aopen(o.id, name.c_str(), H5P_DEFAULT), H5Aclose};
  double v = 0;
  H5Aread(a.id, H5T_NATIVE_DOUBLE, &v);
  return v;
}

long long File::attr_int(const std::string& obj, const std::string& name) const {
  if (!has_attr(obj, name)) throw InputError(path_, obj + "@" + name, "attribute is missing", "attribute " + name);
  Handle o = open_object(id_, obj);
  Handle a{H5Aopen(o.id, name.c_str(), H5P_DEFAULT), H5Aclose};
  long long v = 0;
  H5Aread(a.id, H5T_NATIVE_LLONG, &v);
  return v;
}

}  // namespace breccia::h5
