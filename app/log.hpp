// The console's log lines on standard error. Under systemd (standard error
// is the journal: JOURNAL_STREAM names its device and inode) each line gets
// an sd-daemon priority prefix ("<3>" error, "<4>" warning, "<6>" info), so
// journald files it at its level; elsewhere the lines are plain. Multi-line
// text gets the prefix on every line. Main and monitor threads only: never
// the 1 kHz loop (which counts instead).
#pragma once

#include <string>

namespace visvol::app {

enum class LogLevel : int { error = 3, warning = 4, info = 6 };

// Whether standard error is the journal stream systemd set up for this
// process (JOURNAL_STREAM's "DEVICE:INODE" is standard error's).
bool stderr_is_journal();

// The text as it goes to standard error: each line with the level's prefix
// when `journal`, unchanged otherwise; a final newline added if missing.
std::string log_text(LogLevel level, const std::string& text, bool journal);

// printf-style: formats, prefixes (stderr_is_journal(), checked once) and
// writes to standard error in one write.
void log_printf(LogLevel level, const char* format, ...) __attribute__((format(printf, 2, 3)));
// `text` fit for a log line: control characters and bytes outside printable
// ASCII become '?' (a file name cannot forge a line of its own).
std::string printable(const std::string& text);

}  // namespace visvol::app
