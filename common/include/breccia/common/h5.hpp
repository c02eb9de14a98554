#pragma once
// A thin RAII layer over the HDF5 C API: whole datasets (or ranges of rows) of doubles/ints, string and
// numeric attributes, groups. Enough for particles.h5 and results.h5; nothing clever.
#include <hdf5.h>

#include <cstdint>
#include <string>
#include <vector>

namespace breccia::h5 {

struct RowRun {  // rows [first, first + rows) of a dataset
  hsize_t first = 0, rows = 0;
};

// How write, write_rows and write_runs store an array of more than 65,536 values: in chunks
// of 65,536 rows, through deflate (level 1) by default. ScaleOffset (integers only) is HDF5's
// lossless integer packing instead: each chunk's values less their minimum, in as few bits as
// the chunk's range needs. On results.h5's bond list (3e7 particle indices, int64) it stores
// 68 MB against deflate's 88 MB and writes and reads 2-5 times faster (docs/formats.md).
enum class Filter { Deflate, ScaleOffset };

class File {
public:
  enum class Mode { Read, Create, ReadWrite };
  File(const std::string& path, Mode mode);
#ifdef BRECCIA_PARALLEL_HDF5
  // Every process of `comm` opens the one file together (the MPI-IO driver); from here every
  // call that changes the file (datasets, groups, attributes) is collective: all of them make
  // it, with the same arguments, and write_rows writes each one's rows with collective I/O.
  File(const std::string& path, Mode mode, MPI_Comm comm);
#endif
  ~File();
  File(const File&) = delete;
  File& operator=(const File&) = delete;
  File(File&& o) noexcept : id_(o.id_), transfer_(o.transfer_), path_(std::move(o.path_)) {
    o.id_ = -1;
    o.transfer_ = -1;
  }

  hid_t id() const { return id_; }
  const std::string& path() const { return path_; }
  void flush() const;

  bool exists(const std::string& object_path) const;  // group or dataset, nested paths ok
  void create_group(const std::string& group_path) const;  // creates parents as needed
  std::vector<std::string> children(const std::string& group_path) const;

  // dims: e.g. {N} or {N, 3}. Data is row-major.
  void write(const std::string& path, const std::vector<double>& data, std::vector<hsize_t> dims) const;
  void write(const std::string& path, const std::vector<float>& data, std::vector<hsize_t> dims) const;
  void write(const std::string& path, const std::vector<int64_t>& data, std::vector<hsize_t> dims,
             Filter filter = Filter::Deflate) const;
  void write(const std::string& path, const std::vector<int32_t>& data, std::vector<hsize_t> dims) const;
  void write(const std::string& path, const std::vector<uint8_t>& data, std::vector<hsize_t> dims) const;
  void write_strings(const std::string& path, const std::vector<std::string>& values) const;
  // Rows [first, first + rows) of the dataset `path` of shape dims (its first dimension; every
  // other dimension whole), from data (rows x the other dimensions): the processes that opened
  // the file together each write their own rows, all with the same dims, and the dataset is the
  // one write() makes of the whole array (same type, chunks, compression). A file opened by one
  // process: first 0 and every row, which is write().
  void write_rows(const std::string& path, const double* data, hsize_t first, hsize_t rows, std::vector<hsize_t> dims) const;
  void write_rows(const std::string& path, const float* data, hsize_t first, hsize_t rows, std::vector<hsize_t> dims) const;
  void write_rows(const std::string& path, const uint8_t* data, hsize_t first, hsize_t rows, std::vector<hsize_t> dims) const;
  void write_rows(const std::string& path, const int64_t* data, hsize_t first, hsize_t rows, std::vector<hsize_t> dims) const;
  void write_rows(const std::string& path, const int32_t* data, hsize_t first, hsize_t rows, std::vector<hsize_t> dims) const;
  // The same for several runs of rows per process (ascending, disjoint; data: their rows one
  // after another): a process whose rows are not one range (a distributed run's rows of the
  // results' bond list, in the particle file's order) writes them in one collective call.
  void write_runs(const std::string& path, const int64_t* data, const std::vector<RowRun>& runs,
                  std::vector<hsize_t> dims, Filter filter = Filter::Deflate) const;

  std::vector<hsize_t> dims(const std::string& path) const;
  std::vector<double> read_doubles(const std::string& path) const;
  std::vector<float> read_floats(const std::string& path) const;
  std::vector<int64_t> read_int64(const std::string& path) const;
  std::vector<int32_t> read_int32(const std::string& path) const;
  std::vector<uint8_t> read_uint8(const std::string& path) const;
  std::vector<std::string> read_strings(const std::string& path) const;
  // Rows [first, first + count) of a dataset (its first dimension; every other dimension
  // whole), read through a hyperslab: a process of a distributed run reads its own range
  // and never the whole array. Throws InputError naming the file and dataset when the rows
  // are not all there.
  std::vector<double> read_double_rows(const std::string& path, hsize_t first, hsize_t count) const;
  std::vector<int32_t> read_int32_rows(const std::string& path, hsize_t first, hsize_t count) const;
  std::vector<int64_t> read_int64_rows(const std::string& path, hsize_t first, hsize_t count) const;
  std::vector<uint8_t> read_uint8_rows(const std::string& path, hsize_t first, hsize_t count) const;
  // Runs of rows (ascending, disjoint) of a dataset, read by one selection (their union), their
  // rows one after another: a process's scattered rows (a distributed set-up's rows of a file in
  // the particle file's order) without the whole array. InputError as read_double_rows.
  std::vector<double> read_double_runs(const std::string& path, const std::vector<RowRun>& runs) const;

  // Attributes on an object ("/" for the file).
  void set_attr(const std::string& obj, const std::string& name, const std::string& value) const;
  void set_attr(const std::string& obj, const std::string& name, double value) const;
  void set_attr(const std::string& obj, const std::string& name, long long value) const;
  bool has_attr(const std::string& obj, const std::string& name) const;
  std::string attr_string(const std::string& obj, const std::string& name) const;
  double attr_double(const std::string& obj, const std::string& name) const;
  long long attr_int(const std::string& obj, const std::string& name) const;

private:
  hid_t id_ = -1;
  hid_t transfer_ = -1;  // a collective file's transfer property list (H5FD_MPIO_COLLECTIVE); else none
  std::string path_;
};

}  // namespace breccia::h5
