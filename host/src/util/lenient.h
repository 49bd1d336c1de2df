// Internal: the one rule for input femto can ignore (an unknown or unused parameter, an unused
// -D): an error by default, a warning under --lenient.
#pragma once

#include <string>

#include "femto/error.h"
#include "femto/log.h"

namespace femto::detail {

inline void reject_unless_lenient(bool lenient, const SourceLocation& loc,
                                  const std::string& message) {
    if (!lenient) throw SceneError(loc, message);
    log_warning(loc, message + " -- ignored (--lenient)");
}

}  // namespace femto::detail
