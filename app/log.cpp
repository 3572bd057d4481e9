#include "app/log.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "base/terminal_text.hpp"

namespace visvol::app {

namespace {
constexpr std::size_t kMaxLogBytes = 16384;  // one message
}  // namespace

bool stderr_is_journal() {
  const char* stream = std::getenv("JOURNAL_STREAM");
  if (stream == nullptr) return false;
  unsigned long long device = 0, inode = 0;
  if (std::sscanf(stream, "%llu:%llu", &device, &inode) != 2) return false;
  struct stat st {};
  if (::fstat(STDERR_FILENO, &st) != 0) return false;
  return static_cast<unsigned long long>(st.st_dev) == device && static_cast<unsigned long long>(st.st_ino) == inode;
}

std::string log_text(LogLevel level, const std::string& text, bool journal) {
  const std::string prefix = journal ? "<" + std::to_string(static_cast<int>(level)) + ">" : "";
  std::string out;
  std::size_t begin = 0;
  while (begin < text.size()) {
    const std::size_t end = text.find('\n', begin);
    const std::size_t stop = end == std::string::npos ? text.size() : end;
    out += prefix;
    out.append(text, begin, stop - begin);
    out += '\n';
    begin = stop + 1;
  }
  return out;
}

void log_printf(LogLevel level, const char* format, ...) {
  static const bool journal = stderr_is_journal();
  std::va_list args;
  va_start(args, format);
  std::va_list copy;
  va_copy(copy, args);
  const int n = std::vsnprintf(nullptr, 0, format, copy);
  va_end(copy);
  std::vector<char> buffer(static_cast<std::size_t>(n > 0 ? n : 0) + 1);
  std::vsnprintf(buffer.data(), buffer.size(), format, args);
  va_end(args);
  // what came from outside (a key, a value, a script's token) cannot drive
  // the terminal or flood the journal
  const std::string line = log_text(level, terminal_safe(buffer.data(), kMaxLogBytes), journal);
  std::fwrite(line.data(), 1, line.size(), stderr);
  std::fflush(stderr);
}

std::string printable(const std::string& text) {
  std::string out = text;
  for (char& c : out) {
    if (c < 0x20 || c > 0x7e) c = '?';
  }
  return out;
}

}  // namespace visvol::app
