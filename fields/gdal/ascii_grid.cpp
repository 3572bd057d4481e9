#include "fields/gdal/ascii_grid.hpp"

#include <cpl_vsi.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <memory>
#include <sstream>
#include <vector>

namespace visvol::fields::gdal {

namespace {

// Longer words are no number GDAL reads well (its own limit is 500); kept to
// this length plus one, to tell them apart and to show them.
constexpr std::size_t kMaxCellChars = 64;

struct VsiCloser {
  void operator()(VSILFILE* f) const { VSIFCloseL(f); }
};

// Header keywords of the two formats, lower case (GRASS's without the colon).
bool is_header_key(std::string word) {
  std::transform(word.begin(), word.end(), word.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  static const std::array<const char*, 19> keys = {"ncols",     "nrows",    "xllcorner", "yllcorner", "xllcenter",
                                                   "yllcenter", "cellsize", "dx",        "dy",        "nodata_value",
                                                   "north",     "south",    "east",      "west",      "rows",
                                                   "cols",      "null",     "type",      "multiplier"};
  return std::find(keys.begin(), keys.end(), word) != keys.end();
}

bool is_nodata_key(std::string word) {
  std::transform(word.begin(), word.end(), word.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return word == "nodata_value" || word == "null";
}

// A finite number as GDAL reads these formats (CPLAtofM: '.' or ',' as the
// decimal mark), and nothing after it ("nan" and "inf" are not heights; the
// process keeps the C locale).
bool is_number(std::string token) {
  if (token.size() > kMaxCellChars) return false;
  std::replace(token.begin(), token.end(), ',', '.');
  if (token.empty()) return false;
  char* end = nullptr;
  const double value = std::strtod(token.c_str(), &end);
  return end == token.c_str() + token.size() && std::isfinite(value);
}

// Splits the file into whitespace-separated words, knowing which start a line.
class Words {
 public:
  explicit Words(VSILFILE* f) : f_(f), buf_(1 << 20) {}

  // The next word, or false at the end of the file (or a read error: `failed`).
  bool next(std::string& word, bool& starts_line) {
    word.clear();
    starts_line = at_line_start_;
    for (;;) {
      if (pos_ == len_ && !refill()) return !word.empty();
      const char c = buf_[pos_++];
      if (std::isspace(static_cast<unsigned char>(c))) {
        if (c == '\n') at_line_start_ = true;
        if (!word.empty()) return true;
        starts_line = at_line_start_;
        continue;
      }
      if (word.empty()) at_line_start_ = false;
      if (word.size() <= kMaxCellChars) word.push_back(c);
    }
  }
  bool failed() const { return failed_; }

 private:
  bool refill() {
    len_ = VSIFReadL(buf_.data(), 1, buf_.size(), f_);
    pos_ = 0;
    if (len_ == 0 && !VSIFEofL(f_)) failed_ = true;
    return len_ > 0;
  }

  VSILFILE* f_;
  std::vector<char> buf_;
  std::size_t pos_ = 0, len_ = 0;
  bool at_line_start_ = true;
  bool failed_ = false;
};

// The GRASS form "north:216990" or "north:" and the ESRI form "ncols": the keyword part.
std::string key_of(const std::string& word) { return word.substr(0, word.find(':')); }

// The header's nodata value: a finite number (NaN too, as GDAL writes a
// float grid's), or GRASS's null marker "*". GDAL reads a word that is no
// number as 0, so that every post of 0 m (sea level, a lake) would be taken
// for a hole; an infinite one is no height either.
Status check_nodata_token(const std::string& path, const std::string& token) {
  if (token.empty() || token == "*" || is_number(token)) return Status::ok_status();
  char* end = nullptr;
  if (token.size() <= kMaxCellChars && std::isnan(std::strtod(token.c_str(), &end)) &&
      end == token.c_str() + token.size()) {
    return Status::ok_status();
  }
  return invalid_argument(path + ": its nodata value '" +
                          (token.size() > kMaxCellChars ? token.substr(0, kMaxCellChars) + "..." : token) +
                          "' is not a finite number (a word GDAL reads as 0, taking every post of 0 m for nodata)");
}

}  // namespace

bool is_ascii_grid_driver(const std::string& driver) { return driver == "AAIGrid" || driver == "GRASSASCIIGrid"; }

Status check_ascii_grid_cells(const std::string& path, int nx, int ny) {
  std::unique_ptr<VSILFILE, VsiCloser> f(VSIFOpenL(path.c_str(), "rb"));
  if (!f) return io_error(path + ": cannot open to check its cells");
  Words words(f.get());
  std::string word, nodata_token;
  bool starts_line = false, in_header = true, take_nodata = false;
  const std::size_t cells = static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny);
  std::size_t n = 0;
  while (words.next(word, starts_line)) {
    // Header lines start with a keyword; the first line that does not is data.
    if (in_header && starts_line) in_header = is_header_key(key_of(word));
    if (in_header) {
      if (take_nodata) nodata_token = word;
      const std::size_t colon = word.find(':');
      if (starts_line && is_nodata_key(key_of(word)) && colon != std::string::npos && colon + 1 < word.size()) {
        nodata_token = word.substr(colon + 1);  // "null:*"
      }
      take_nodata = starts_line && is_nodata_key(key_of(word));
      continue;
    }
    if (n == 0) {
      const Status nodata = check_nodata_token(path, nodata_token);
      if (!nodata.ok()) return nodata;
    }
    if (n < cells && !is_number(word) && word != nodata_token) {
      std::ostringstream msg;
      msg << path << ": cell (" << n % static_cast<std::size_t>(nx) << ", " << n / static_cast<std::size_t>(nx)
          << ") (column, row from the north-west) is '"
          << (word.size() > kMaxCellChars ? word.substr(0, kMaxCellChars) + "..." : word) << "', not a number"
          << (nodata_token.empty() ? "" : " nor the nodata value '" + nodata_token + "'")
          << "; GDAL would read it as 0 m";
      return invalid_argument(msg.str());
    }
    ++n;
  }
  if (words.failed()) return io_error(path + ": read failed while checking its cells");
  if (n != cells) {
    std::ostringstream msg;
    msg << path << ": has " << n << " cells after its header; its size " << nx << " x " << ny << " needs " << cells;
    return invalid_argument(msg.str());
  }
  return Status::ok_status();
}

}  // namespace visvol::fields::gdal
