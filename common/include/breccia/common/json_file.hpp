#pragma once
// JSON files of every stage (summary.json, post.json) through nlohmann/json: strings escaped,
// keys in the order written (ordered_json), and numbers that are not finite written as null,
// so the file stays JSON that any strict parser reads (JSON has no NaN or Infinity).
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace breccia {

using Json = nlohmann::ordered_json;

// v when finite, null otherwise.
Json json_number(double v);

// j[key] = json_number(v); when v is not finite and non_finite is given, key is appended
// to it (summary.json lists such keys, so a reader can tell "blew up" from "absent").
void set_json_number(Json& j, const std::string& key, double v, std::vector<std::string>* non_finite = nullptr);

// The file's text: two-space indentation and a final newline. A string that is not valid
// UTF-8 (a path in another encoding) has its bad bytes replaced rather than failing the write.
std::string json_text(const Json& j);

// json_text(j) written atomically (output_file.hpp).
void write_json_file(const std::filesystem::path& path, const Json& j);

// A JSON file parsed strictly; InputError naming the file when it is missing or not JSON.
Json read_json_file(const std::filesystem::path& path);

}  // namespace breccia
