#include "drivers/render/transfer_function.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <fstream>

namespace visvol::render {
namespace {

TEST(TransferFunction, ParsesPointsCommentsAndBothSpellings) {
  const char* text =
      "# a test transfer function\n"
      "colour 0 1 0 0   # red when hidden\n"
      "\n"
      "color 0.5, 0, 1, 0\n"
      "colour\t1 0 0 1\n"
      "opacity 0 0\n"
      "opacity 1 0.5\n";
  Result<TransferFunction> tf = parse_transfer_function(text, "tf.txt");
  ASSERT_TRUE(tf.ok()) << tf.status().message();
  ASSERT_EQ(tf->colour.size(), 3u);
  ASSERT_EQ(tf->opacity.size(), 2u);
  EXPECT_DOUBLE_EQ(tf->colour[1].fp, 0.5);
  EXPECT_DOUBLE_EQ(tf->colour[1].g, 1.0);
  EXPECT_DOUBLE_EQ(tf->opacity[1].opacity, 0.5);
}

TEST(TransferFunction, InterpolatesLinearlyAndHoldsTheEnds) {
  TransferFunction tf;
  tf.colour = {{0.2, 1, 0, 0}, {0.6, 0, 0, 1}};
  tf.opacity = {{0.0, 0.0}, {1.0, 0.8}};
  ASSERT_TRUE(validate(tf, "tf").ok());
  const Rgb below = colour_at(tf, 0.0), mid = colour_at(tf, 0.4), above = colour_at(tf, 1.0);
  EXPECT_DOUBLE_EQ(below.r, 1.0);
  EXPECT_DOUBLE_EQ(above.b, 1.0);
  EXPECT_NEAR(mid.r, 0.5, 1e-12);
  EXPECT_NEAR(mid.b, 0.5, 1e-12);
  EXPECT_NEAR(opacity_at(tf, 0.25), 0.2, 1e-12);
  EXPECT_DOUBLE_EQ(opacity_at(tf, 2.0), 0.8);
}

TEST(TransferFunction, OpacityPerStepComposesToOpacityPerUnit) {
  // two half-unit steps collect what one unit does; full opacity stays full
  const double a = 0.3;
  const double half = opacity_for_step(a, 0.5);
  EXPECT_NEAR(1 - (1 - half) * (1 - half), a, 1e-12);
  EXPECT_DOUBLE_EQ(opacity_for_step(1.0, 0.01), 1.0);
  EXPECT_DOUBLE_EQ(opacity_for_step(0.0, 10.0), 0.0);
}

TEST(TransferFunction, DefaultIsValidRedToBlue) {
  const TransferFunction tf = default_transfer_function();
  ASSERT_TRUE(validate(tf, "default").ok());
  EXPECT_GT(colour_at(tf, 0).r, colour_at(tf, 0).b);    // hidden: red
  EXPECT_GT(colour_at(tf, 1).b, colour_at(tf, 1).r);    // seen: blue
  EXPECT_GT(opacity_at(tf, 0.1), opacity_at(tf, 0.9));  // hidden air is the denser fog
}

TEST(TransferFunction, ErrorsNameTheFileTheLineAndTheProblem) {
  struct Case {
    const char* text;
    const char* expected;
  } cases[] = {
      {"colour 0 1 0 0\nopacity 0 0\nshade 1 2\n", "tf.txt: line 3: 'shade' is not 'colour' or 'opacity'"},
      {"colour 0 1 0\nopacity 0 0\n", "tf.txt: line 1: colour takes 4 numbers (F R G B), found 3"},
      {"colour 0 1 0 0\nopacity 0 0 1\n", "tf.txt: line 2: opacity takes 2 numbers (F A), found 3"},
      {"colour 0 1 0 0\nopacity 0 abc\n", "tf.txt: line 2: A 'abc' is not a finite number"},
      {"colour 0 1 0 0\nopacity 0 nan\n", "tf.txt: line 2: A 'nan' is not a finite number"},
      {"colour 0 1.5 0 0\nopacity 0 0\n", "tf.txt: line 1: R 1.5 is outside [0, 1]"},
      {"colour -0.1 1 0 0\nopacity 0 0\n", "tf.txt: line 1: F -0.1 is outside [0, 1]"},
      {"colour 0.5 1 0 0\ncolour 0.5 0 0 1\nopacity 0 0\n",
       "tf.txt: line 2: F 0.5 is not above the previous colour point's 0.5"},
      {"colour 0 1 0 0\n", "tf.txt: no opacity points"},
      {"# nothing\nopacity 0 0\n", "tf.txt: no colour points"},
  };
  for (const Case& c : cases) {
    Result<TransferFunction> tf = parse_transfer_function(c.text, "tf.txt");
    ASSERT_FALSE(tf.ok()) << c.text;
    EXPECT_EQ(tf.status().code(), Errc::invalid_argument);
    EXPECT_NE(tf.status().message().find(c.expected), std::string::npos)
        << "got: " << tf.status().message() << "\nwanted: " << c.expected;
  }
}

TEST(TransferFunction, RefusesMoreThanTheMaximumPoints) {
  std::string text = "opacity 0 0\n";
  for (std::size_t i = 0; i <= kMaxTransferPoints; ++i) {
    text += "colour " + std::to_string(static_cast<double>(i) / (kMaxTransferPoints + 1)) + " 0 0 0\n";
  }
  Result<TransferFunction> tf = parse_transfer_function(text, "many.txt");
  ASSERT_FALSE(tf.ok());
  EXPECT_NE(tf.status().message().find("more than 64 colour points"), std::string::npos) << tf.status().message();
}

TEST(TransferFunction, ReadsAFileAndNamesAMissingOne) {
  const std::string path = ::testing::TempDir() + "/tf_" + std::to_string(::getpid()) + ".txt";
  std::ofstream(path) << "colour 0 0 0 0\ncolour 1 1 1 1\nopacity 0 0.1\n";
  Result<TransferFunction> tf = read_transfer_function(path);
  ASSERT_TRUE(tf.ok()) << tf.status().message();
  EXPECT_EQ(tf->colour.size(), 2u);
  std::remove(path.c_str());
  Result<TransferFunction> missing = read_transfer_function(path);
  ASSERT_FALSE(missing.ok());
  EXPECT_EQ(missing.status().code(), Errc::io);
  EXPECT_NE(missing.status().message().find(path), std::string::npos);
}

}  // namespace
}  // namespace visvol::render
