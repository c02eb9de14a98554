#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>

#include "breccia/common/error.hpp"
#include "breccia/common/json_file.hpp"

using namespace breccia;

TEST(JsonFile, NonFiniteNumbersAreNullAndListed) {
  Json j;
  std::vector<std::string> non_finite;
  set_json_number(j, "a", 1.5, &non_finite);
  set_json_number(j, "b", std::numeric_limits<double>::quiet_NaN(), &non_finite);
  set_json_number(j, "c", -std::numeric_limits<double>::infinity(), &non_finite);
  j["d"] = json_number(std::numeric_limits<double>::infinity());
  EXPECT_EQ(non_finite, (std::vector<std::string>{"b", "c"}));
  const std::string text = json_text(j);
  EXPECT_EQ(text.back(), '\n');
  const Json back = Json::parse(text);  // strict: NaN or Infinity tokens would throw
  EXPECT_EQ(back["a"], 1.5);
  EXPECT_TRUE(back["b"].is_null() && back["c"].is_null() && back["d"].is_null());
  // Keys in the order written.
  EXPECT_EQ(back.begin().key(), "a");
}

TEST(JsonFile, StringsRoundTripEscaped) {
  const std::string path = "C:\\runs\\\"odd\"\n\tname";
  const auto file = std::filesystem::path(::testing::TempDir()) / "escaped.json";
  write_json_file(file, Json{{"path", path}});
  EXPECT_EQ(read_json_file(file).at("path"), path);
}

TEST(JsonFile, ReadRejectsWhatIsNotJson) {
  const auto file = std::filesystem::path(::testing::TempDir()) / "nan.json";
  std::ofstream(file) << "{\"x\": NaN}\n";
  try {
    read_json_file(file);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), file.string());
  }
}
