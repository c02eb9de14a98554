#include "breccia/common/output_file.hpp"

#include <cstdio>
#include <fstream>
#include <system_error>

#include "breccia/common/error.hpp"

namespace breccia {

OutputFile::OutputFile(std::filesystem::path final_path)
    : final_(std::move(final_path)), temp_(temp_path_of(final_)) {
  if (final_.has_parent_path()) std::filesystem::create_directories(final_.parent_path());
}

OutputFile::~OutputFile() {
  if (!committed_) {
    std::error_code ec;
    std::filesystem::remove(temp_, ec);
  }
}

std::filesystem::path OutputFile::temp_path_of(const std::filesystem::path& final_path) {
  return final_path.string() + ".partial";
}

void OutputFile::commit() {
  std::error_code ec;
  std::filesystem::rename(temp_, final_, ec);
  if (ec) throw RunError("cannot rename " + temp_.string() + " to " + final_.string() + ": " + ec.message());
  committed_ = true;
}

void write_text_file(const std::filesystem::path& path, const std::string& content) {
  OutputFile out(path);
  {
    std::ofstream f(out.temp_path());
    f << content;
    if (!f) throw RunError("cannot write " + out.temp_path().string());
  }
  out.commit();
}

std::string folder_write_problem(const std::filesystem::path& folder) {
  const std::filesystem::path f = folder.empty() ? std::filesystem::path(".") : folder;
  std::error_code ec;
  std::filesystem::create_directories(f, ec);
  if (ec) return ec.message();
  const std::filesystem::path probe = f / ".breccia-write-probe";
  std::FILE* file = std::fopen(probe.c_str(), "w");
  if (!file) return "cannot create a file there";
  std::fclose(file);
  std::remove(probe.c_str());
  return "";
}

}  // namespace breccia
