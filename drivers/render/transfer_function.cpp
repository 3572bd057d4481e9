#include "drivers/render/transfer_function.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>

#include "io/input_file.hpp"

namespace visvol::render {

namespace {

// 64 points of each kind take a few kilobytes; anything far larger is not one
constexpr std::size_t kMaxTransferFileBytes = 1u << 20;

std::string number_text(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

bool in_unit(double v) { return v >= 0.0 && v <= 1.0; }

// Piecewise-linear interpolation over points sorted by fp; `value` reads a point.
template <class Point, class Value>
auto interpolate(const std::vector<Point>& points, double fp, Value value) {
  if (fp <= points.front().fp) return value(points.front());
  if (fp >= points.back().fp) return value(points.back());
  const auto upper =
      std::upper_bound(points.begin(), points.end(), fp, [](double f, const Point& p) { return f < p.fp; });
  const Point& b = *upper;
  const Point& a = *(upper - 1);
  const double t = (fp - a.fp) / (b.fp - a.fp);
  const auto va = value(a), vb = value(b);
  return va + (vb - va) * t;
}

struct Triple {
  double r, g, b;
  Triple operator+(const Triple& o) const { return {r + o.r, g + o.g, b + o.b}; }
  Triple operator-(const Triple& o) const { return {r - o.r, g - o.g, b - o.b}; }
  Triple operator*(double s) const { return {r * s, g * s, b * s}; }
};

// Splits a line into words (spaces, tabs, commas).
std::vector<std::string> words_of(const std::string& line) {
  std::string clean = line;
  for (char& c : clean) {
    if (c == ',' || c == '\t' || c == '\r') c = ' ';
  }
  std::istringstream in(clean);
  std::vector<std::string> out;
  std::string w;
  while (in >> w) out.push_back(w);
  return out;
}

bool parse_double(const std::string& word, double& out) {
  char* end = nullptr;
  errno = 0;
  out = std::strtod(word.c_str(), &end);
  return end != word.c_str() && *end == '\0' && errno != ERANGE && std::isfinite(out);
}

}  // namespace

// Hidden air (low F_p) is the thickest fog, well-seen air clear: what a
// stealth planner looks for, and the terrain stays visible through it.
TransferFunction default_transfer_function() {
  TransferFunction tf;
  tf.colour = {{0.00, 0.647, 0.000, 0.149},
               {0.25, 0.957, 0.427, 0.263},
               {0.50, 0.996, 0.878, 0.565},
               {0.75, 0.455, 0.678, 0.820},
               {1.00, 0.192, 0.212, 0.584}};
  tf.opacity = {{0.00, 0.20}, {0.25, 0.10}, {0.50, 0.02}, {1.00, 0.00}};
  return tf;
}

Status validate(const TransferFunction& tf, const std::string& name) {
  if (tf.colour.empty()) return invalid_argument(name + ": no colour points (need 'colour F R G B')");
  if (tf.opacity.empty()) return invalid_argument(name + ": no opacity points (need 'opacity F A')");
  if (tf.colour.size() > kMaxTransferPoints || tf.opacity.size() > kMaxTransferPoints) {
    return invalid_argument(name + ": more than " + std::to_string(kMaxTransferPoints) + " points of one kind");
  }
  for (std::size_t i = 0; i < tf.colour.size(); ++i) {
    const ColourPoint& p = tf.colour[i];
    if (!in_unit(p.fp) || !in_unit(p.r) || !in_unit(p.g) || !in_unit(p.b)) {
      return invalid_argument(name + ": colour point " + std::to_string(i) + " has a value outside [0, 1]");
    }
    if (i > 0 && !(p.fp > tf.colour[i - 1].fp)) {
      return invalid_argument(name + ": colour point " + std::to_string(i) + " is not above the previous F");
    }
  }
  for (std::size_t i = 0; i < tf.opacity.size(); ++i) {
    const OpacityPoint& p = tf.opacity[i];
    if (!in_unit(p.fp) || !in_unit(p.opacity)) {
      return invalid_argument(name + ": opacity point " + std::to_string(i) + " has a value outside [0, 1]");
    }
    if (i > 0 && !(p.fp > tf.opacity[i - 1].fp)) {
      return invalid_argument(name + ": opacity point " + std::to_string(i) + " is not above the previous F");
    }
  }
  return Status::ok_status();
}

Result<TransferFunction> parse_transfer_function(std::string_view text, const std::string& name) {
  TransferFunction tf;
  std::istringstream in{std::string(text)};
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    const std::size_t hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    const std::vector<std::string> w = words_of(line);
    if (w.empty()) continue;
    const std::string where = name + ": line " + std::to_string(line_no) + ": ";
    const bool colour = w[0] == "colour" || w[0] == "color";
    if (!colour && w[0] != "opacity") {
      return invalid_argument(where + "'" + w[0] + "' is not 'colour' or 'opacity'");
    }
    const std::size_t expected = colour ? 4 : 2;
    if (w.size() - 1 != expected) {
      return invalid_argument(where + w[0] + " takes " + std::to_string(expected) + " numbers (" +
                              (colour ? "F R G B" : "F A") + "), found " + std::to_string(w.size() - 1));
    }
    double v[4] = {0, 0, 0, 0};
    static const char* const kColourNames[] = {"F", "R", "G", "B"};
    static const char* const kOpacityNames[] = {"F", "A"};
    for (std::size_t n = 0; n < expected; ++n) {
      const char* what = colour ? kColourNames[n] : kOpacityNames[n];
      if (!parse_double(w[n + 1], v[n])) {
        return invalid_argument(where + what + " '" + w[n + 1] + "' is not a finite number");
      }
      if (!in_unit(v[n])) {
        return invalid_argument(where + what + " " + number_text(v[n]) + " is outside [0, 1]");
      }
    }
    const double previous =
        colour ? (tf.colour.empty() ? -1.0 : tf.colour.back().fp) : (tf.opacity.empty() ? -1.0 : tf.opacity.back().fp);
    if (!(v[0] > previous)) {
      return invalid_argument(where + "F " + number_text(v[0]) + " is not above the previous " + w[0] + " point's " +
                              number_text(previous));
    }
    if ((colour ? tf.colour.size() : tf.opacity.size()) >= kMaxTransferPoints) {
      return invalid_argument(where + "more than " + std::to_string(kMaxTransferPoints) + " " + w[0] + " points");
    }
    if (colour) {
      tf.colour.push_back({v[0], v[1], v[2], v[3]});
    } else {
      tf.opacity.push_back({v[0], v[1]});
    }
  }
  VISVOL_RETURN_IF_ERROR(validate(tf, name));
  return tf;
}

Result<TransferFunction> read_transfer_function(const std::string& path) {
  Result<std::string> text = read_input_file(path, kMaxTransferFileBytes);
  if (!text.ok()) return text.status();
  return parse_transfer_function(*text, path);
}

Rgb colour_at(const TransferFunction& tf, double fp) {
  const Triple t = interpolate(tf.colour, fp, [](const ColourPoint& p) { return Triple{p.r, p.g, p.b}; });
  return {t.r, t.g, t.b};
}

double opacity_at(const TransferFunction& tf, double fp) {
  return interpolate(tf.opacity, fp, [](const OpacityPoint& p) { return p.opacity; });
}

double opacity_for_step(double opacity_per_unit, double step_units) {
  const double a = std::clamp(opacity_per_unit, 0.0, 1.0);
  if (a >= 1.0) return 1.0;
  return 1.0 - std::pow(1.0 - a, step_units);
}

}  // namespace visvol::render
