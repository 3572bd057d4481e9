// The build's version: the project's release number and the commit it was
// built from ("visvol 0.1.0 (commit 1a2b3c4)", "-dirty" when the tree had
// uncommitted changes, "unknown" outside a git checkout). Every program
// prints it for --version. Stamped at build time (base/version.cpp.in).
#pragma once

namespace visvol {

const char* version_number();  // "0.1.0"
const char* version_commit();  // "1a2b3c4", "1a2b3c4-dirty" or "unknown"
// "NAME 0.1.0 (commit 1a2b3c4)": what --version prints for program NAME.
const char* version_line(const char* program);
// Every program's first line: true (after printing version_line) when an
// argument is --version, and main returns 0.
bool print_version_if_asked(int argc, char** argv, const char* program);

}  // namespace visvol
