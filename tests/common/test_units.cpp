#include <gtest/gtest.h>

#include <fstream>
#include <functional>

#include "breccia/common/error.hpp"
#include "breccia/common/units.hpp"
#include "breccia/common/yaml_input.hpp"

using namespace breccia;

TEST(Units, PlainNumbersAreSIAndSuffixesConvert) {
  EXPECT_DOUBLE_EQ(parse_quantity("2.5", Quantity::Pressure, "f", "x"), 2.5);
  EXPECT_DOUBLE_EQ(parse_quantity("1 GPa", Quantity::Pressure, "f", "x"), 1e9);
  EXPECT_DOUBLE_EQ(parse_quantity("140 us", Quantity::Time, "f", "x"), 140e-6);
  EXPECT_DOUBLE_EQ(parse_quantity("2320 kg/m3", Quantity::Density, "f", "x"), 2320.0);
  EXPECT_DOUBLE_EQ(parse_quantity("25 J/m2", Quantity::FractureEnergy, "f", "x"), 25.0);
}

TEST(Units, WrongKindOfUnitNamesFileFieldAndAcceptedUnits) {
  try {
    parse_quantity("5 mm", Quantity::Pressure, "case.yaml", "loads[0].peak_pressure");
    FAIL() << "a length given for a pressure must be rejected";
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("case.yaml"), std::string::npos);
    EXPECT_NE(msg.find("loads[0].peak_pressure"), std::string::npos);
    EXPECT_NE(msg.find("MPa"), std::string::npos);
  }
}

TEST(YamlInput, UnknownKeyIsRejectedWithAllowedKeys) {
  const std::string path = ::testing::TempDir() + "/bad_key.yaml";
  std::ofstream(path) << "material:\n  densty: 2000\n";
  const Section root = Section::load_file(path);
  const Section mat = root.section("material");
  try {
    mat.allow_only({"density", "youngs_modulus"});
    FAIL();
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("material.densty"), std::string::npos);
    EXPECT_NE(msg.find("density"), std::string::npos);
  }
}

TEST(YamlInput, SyntaxErrorNamesTheLine) {
  const std::string path = ::testing::TempDir() + "/bad_syntax.yaml";
  std::ofstream(path) << "a: 1\nb: [1, 2\n";
  try {
    Section::load_file(path);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("line"), std::string::npos);
  }
}

TEST(YamlInput, DuplicateKeysAreRejectedWithBothLines) {
  // yaml-cpp keeps the first of two equal keys: a second `model:` block would be dropped.
  const std::string path = ::testing::TempDir() + "/duplicate_key.yaml";
  std::ofstream(path) << "name: x\nmodel: {type: pmb}\ntime: {steps: 1}\nmodel: {type: lps}\n";
  try {
    Section::load_file(path);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("model"), std::string::npos) << msg;
    EXPECT_NE(msg.find("lines 2 and 4"), std::string::npos) << msg;
  }
  // Nested maps and maps inside lists too, named by their path.
  std::ofstream(path) << "materials:\n  - {name: a, density: 1}\n  - name: b\n    density: 1\n    density: 2\n";
  try {
    Section::load_file(path);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("materials[1].density"), std::string::npos) << msg;
    EXPECT_NE(msg.find("lines 4 and 5"), std::string::npos) << msg;
  }
}

// Found in review (2026-12-08): numbers are decimal. stod read "0x10" as 16 and "0x1p-24" as a
// time step, yaml-cpp read an integer "010" as octal 8 (and "0x10" as 16); a number beyond a
// double's range was "not a number"; a small negative value printed as -0.000000.
TEST(Units, NumbersAreDecimalAndOutOfRangeOrNegativeValuesAreNamedAsSuch) {
  const auto message_of = [](const std::function<void()>& f) {
    try {
      f();
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("(accepted)");
  };
  EXPECT_NE(message_of([] { parse_quantity("0x1p-24", Quantity::Time, "f", "x"); }).find("not a decimal number"),
            std::string::npos);
  EXPECT_NE(message_of([] { parse_quantity("0x10 s", Quantity::Time, "f", "x"); }).find("not a decimal number"),
            std::string::npos);
  EXPECT_NE(message_of([] { parse_quantity("1e400 Pa", Quantity::Pressure, "f", "x"); }).find("out of the range"),
            std::string::npos);
  const std::string path = ::testing::TempDir() + "/numbers.yaml";
  std::ofstream(path) << "steps: 010\nhex: 0x10\nsigned: +7\ndt: -5 ns\n";
  const Section root = Section::load_file(path);
  EXPECT_EQ(root.integer("steps"), 10);
  EXPECT_EQ(root.integer("signed"), 7);
  EXPECT_NE(message_of([&] { root.integer("hex"); }).find("'0x10' is not an integer"), std::string::npos);
  EXPECT_NE(message_of([&] { root.positive("dt", Quantity::Time); }).find("value -5e-09 is not positive"),
            std::string::npos);
}
