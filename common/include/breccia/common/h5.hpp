#pragma once
// A thin RAII layer over the HDF5 C API: whole datasets (or ranges of rows) of doubles/ints, string and
// numeric attributes, groups. Enough for particles.h5 and results.h5; nothing clever.
#include <hdf5.h>

#include <cstdint>
#include <string>
#include <vector>

namespace breccia::h5 {

class File {
public:
  enum class Mode { Read, Create, ReadWrite };
  File(const std::string& path, Mode mode);
  ~File();
  File(const File&) = delete;
  File& operator=(const File&) = delete;
  File(File&& o) noexcept : id_(o.id_), path_(std::move(o.path_)) { o.id_ = -1; }

  hid_t id() const { return id_; }
  const std::string& path() const { return path_; }
  void flush() const;

  bool exists(const std::string& object_path) const;  // group or dataset, nested paths ok
  void create_group(const std::string& group_path) const;  // creates parents as needed
  std::vector<std::string> children(const std::string& group_path) const;

  // dims: e.g. {N} or {N, 3}. Data is row-major.
  void write(const std::string& path, const std::vector<double>& data, std::vector<hsize_t> dims) const;
  void write(const std::string& path, const std::vector<float>& data, std::vector<hsize_t> dims) const;
  void write(const std::string& path, const std::vector<int64_t>& data, std::vector<hsize_t> dims) const;
  void write(const std::string& path, const std::vector<int32_t>& data, std::vector<hsize_t> dims) const;
  void write(const std::string& path, const std::vector<uint8_t>& data, std::vector<hsize_t> dims) const;
  void write_strings(const std::string& path, const std::vector<std::string>& values) const;

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
  std::string path_;
};

}  // namespace breccia::h5
