// femto public API: warnings and information printed by the host (to stderr).
#pragma once

#include <string>

#include "femto/error.h"

namespace femto {

/// Prints "warning: <loc>: <message>" unless warnings are silenced; thread-safe.
void log_warning(const SourceLocation& loc, const std::string& message);
inline void log_warning(const std::string& message) { log_warning(SourceLocation{}, message); }
/// Silences (or restores) this process's warnings and notes; they are still counted. The
/// processes of a distributed render other than rank 0 are silenced: rank 0 says it once.
void silence_log(bool silent);
/// Number of warnings printed so far in this process.
int warning_count();

/// Prints "note: <loc>: <message>": input femto accepts but gives no meaning (a Mitsuba
/// parameter that has no effect in femto). Not a warning: warning_count() is unchanged.
void log_note(const SourceLocation& loc, const std::string& message);

}  // namespace femto
