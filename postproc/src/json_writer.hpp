#pragma once
// A minimal streaming JSON writer for post.json (no dependency for one small file).
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

namespace breccia::postproc {

class JsonWriter {
public:
  JsonWriter() { s_.precision(10); }
  JsonWriter& begin_object(const std::string& key = "") { return open(key, '{'); }
  JsonWriter& begin_array(const std::string& key = "") { return open(key, '['); }
  JsonWriter& end_object() { return close('}'); }
  JsonWriter& end_array() { return close(']'); }
  JsonWriter& value(const std::string& key, double v) {
    prefix(key);
    if (std::isfinite(v)) s_ << v;
    else s_ << "null";
    return *this;
  }
  JsonWriter& value(const std::string& key, long long v) { prefix(key); s_ << v; return *this; }
  JsonWriter& value(const std::string& key, int v) { return value(key, static_cast<long long>(v)); }
  JsonWriter& value(const std::string& key, size_t v) { return value(key, static_cast<long long>(v)); }
  JsonWriter& value(const std::string& key, bool v) { prefix(key); s_ << (v ? "true" : "false"); return *this; }
  JsonWriter& value(const std::string& key, const std::string& v) { prefix(key); s_ << quote(v); return *this; }
  JsonWriter& value(const std::string& key, const char* v) { return value(key, std::string(v)); }
  JsonWriter& null(const std::string& key) { prefix(key); s_ << "null"; return *this; }
  std::string str() const { return s_.str() + "\n"; }

private:
  JsonWriter& open(const std::string& key, char c) {
    prefix(key);
    s_ << c;
    first_.push_back(true);
    return *this;
  }
  JsonWriter& close(char c) {
    const bool empty = first_.back();
    first_.pop_back();
    if (!empty) newline();
    s_ << c;
    return *this;
  }
  void prefix(const std::string& key) {
    if (!first_.empty()) {
      if (!first_.back()) s_ << ',';
      first_.back() = false;
      newline();
    }
    if (!key.empty()) s_ << quote(key) << ": ";
  }
  void newline() { s_ << '\n' << std::string(2 * first_.size(), ' '); }
  static std::string quote(const std::string& v) {
    std::string out = "\"";
    for (char c : v) {
      if (c == '"' || c == '\\') { out += '\\'; out += c; }
      else if (c == '\n') out += "\\n";
      else if (static_cast<unsigned char>(c) < 0x20) { char b[8]; std::snprintf(b, sizeof b, "\\u%04x", c); out += b; }
      else out += c;
    }
    return out + "\"";
  }
  std::ostringstream s_;
  std::vector<bool> first_;
};

}  // namespace breccia::postproc
