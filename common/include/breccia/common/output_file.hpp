#pragma once
// Outputs are written to "<name>.partial" and renamed when complete, so a reader never
// sees a half-written file passed off as finished, and a failed run never clobbers the
// previous good file of the same name.
#include <filesystem>
#include <string>

namespace breccia {

class OutputFile {
public:
  explicit OutputFile(std::filesystem::path final_path);
  ~OutputFile();  // removes the partial file if commit() was not called
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  const std::filesystem::path& temp_path() const { return temp_; }
  const std::filesystem::path& final_path() const { return final_; }
  void commit();  // atomic rename onto the final name
  // The partial file's name: processes that write one file together all open this one.
  static std::filesystem::path temp_path_of(const std::filesystem::path& final_path);

private:
  std::filesystem::path final_, temp_;
  bool committed_ = false;
};

// Why `folder` cannot take a tool's output files ("" when it can): it is made (with its
// parents) if missing, and a file is created and removed in it. The tools ask it before their
// work (cli::require_writable_folder), so that an unwritable output path is bad input at once.
std::string folder_write_problem(const std::filesystem::path& folder);

// Write a whole text file atomically.
void write_text_file(const std::filesystem::path& path, const std::string& content);

}  // namespace breccia
