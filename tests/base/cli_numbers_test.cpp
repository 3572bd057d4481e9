#include "base/cli_numbers.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <string>
#include <vector>

#include "../support/scratch.hpp"

namespace visvol {
namespace {

// Parses `args` (after the program's name) into an application of numeric
// options; "" when it parsed, else CLI11's message.
struct Numbers {
  CLI::App app{"numbers"};
  int segments = 0;
  unsigned domain = 0;
  double speed = 0;
  std::vector<double> from;
  int verbose = 0;
  double clearance = 0;

  Numbers() {
    app.add_option("--segments", segments);
    app.add_option("--domain", domain)->check(CLI::Range(0u, 232u));
    app.add_option("--speed", speed);
    app.add_option("--from", from)->expected(3);
    app.add_flag("-v", verbose);
    app.set_config("--config");
    CLI::App* plan = app.add_subcommand("plan");
    plan->add_option("--clearance", clearance);
    decimal_numbers(app);
  }
  std::string parse(std::vector<std::string> args) {
    std::vector<std::string> argv_text{"numbers"};
    argv_text.insert(argv_text.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (std::string& a : argv_text) argv.push_back(a.data());
    try {
      app.parse(static_cast<int>(argv.size()), argv.data());
    } catch (const CLI::ParseError& e) {
      return e.what();
    }
    return {};
  }
};

TEST(DecimalNumbers, AnIntegerWithALeadingZeroIsDecimalNotOctal) {
  Numbers n;
  // CLI11 alone read "010" as octal eight
  ASSERT_EQ(n.parse({"--segments", "010", "--domain", "0232"}), "");
  EXPECT_EQ(n.segments, 10);
  EXPECT_EQ(n.domain, 232u);
  Numbers signed_ones;
  ASSERT_EQ(signed_ones.parse({"--segments", "-007"}), "");
  EXPECT_EQ(signed_ones.segments, -7);
  Numbers plus;
  ASSERT_EQ(plus.parse({"--segments", "+12"}), "");
  EXPECT_EQ(plus.segments, 12);
}

TEST(DecimalNumbers, OtherBasesAndFormsAreRefusedNamingTheOption) {
  for (const char* value : {"0x10", "0b11", "1e2", "12abc", " 10", "+", ""}) {
    Numbers n;
    const std::string error = n.parse({"--segments", value});
    EXPECT_NE(error.find("--segments"), std::string::npos) << value << ": " << error;
    EXPECT_EQ(n.segments, 0) << value;
  }
  Numbers hex;
  EXPECT_NE(hex.parse({"--segments", "0x10"}).find("'0x10' is not a whole number in decimal digits"),
            std::string::npos);
}

TEST(DecimalNumbers, AnUnsignedOptionRefusesANegativeNumber) {
  // strtoull wraps "-1" to 2^64 - 1
  Numbers n;
  const std::string error = n.parse({"--domain", "-1"});
  EXPECT_NE(error.find("--domain"), std::string::npos) << error;
  EXPECT_NE(error.find("negative"), std::string::npos) << error;
}

TEST(DecimalNumbers, ARealMustBeDecimalOrAWordForInfinityOrNan) {
  // strtold read all of these, " 0x10" as sixteen
  for (const char* value : {"0x10", "-0X1p3", "+0x.8", " 0x10", " 10", "10 ", "1e", ".", "5m", "0b1"}) {
    Numbers n;
    const std::string error = n.parse({"--speed", value});
    EXPECT_NE(error.find("is not a number in decimal"), std::string::npos) << value << ": " << error;
    EXPECT_EQ(n.speed, 0) << value;
  }
  for (const char* value : {"5.", ".5", "-2.5E-3", "+7"}) {
    Numbers n;
    EXPECT_EQ(n.parse({"--speed", value}), "") << value;
  }
  Numbers decimal;
  ASSERT_EQ(decimal.parse({"--speed", "010.5"}), "");
  EXPECT_EQ(decimal.speed, 10.5);
  Numbers exponent;
  ASSERT_EQ(exponent.parse({"--speed", "1e1"}), "");
  EXPECT_EQ(exponent.speed, 10);
  // infinities and NaN reach the option's own check, which names its range
  Numbers infinite;
  ASSERT_EQ(infinite.parse({"--speed", "inf"}), "");
  EXPECT_TRUE(std::isinf(infinite.speed));
}

TEST(DecimalNumbers, EveryValueOfAListAndEveryLevelOfSubcommands) {
  Numbers list;
  EXPECT_NE(list.parse({"--from", "1", "0x2", "3"}).find("is not a number in decimal"), std::string::npos);
  Numbers nested;
  EXPECT_NE(nested.parse({"plan", "--clearance", "0x1e"}).find("--clearance"), std::string::npos);
  Numbers fine;
  ASSERT_EQ(fine.parse({"plan", "--clearance", "030"}), "");
  EXPECT_EQ(fine.clearance, 30);
}

TEST(DecimalNumbers, FlagsAreLeftAlone) {
  Numbers n;
  ASSERT_EQ(n.parse({"-v", "-v"}), "");
  EXPECT_EQ(n.verbose, 2);
}

TEST(DecimalNumbers, AConfigurationFilesValuesToo) {
  const std::string path = test::scratch_path("cli_numbers");  // TOML, whatever its name
  std::ofstream(path) << "segments = 010\n";
  Numbers n;
  ASSERT_EQ(n.parse({"--config", path}), "");
  EXPECT_EQ(n.segments, 10);
  std::ofstream(path) << "segments = 0x10\n";
  Numbers hex;
  EXPECT_NE(hex.parse({"--config", path}).find("--segments"), std::string::npos);
}

}  // namespace
}  // namespace visvol
