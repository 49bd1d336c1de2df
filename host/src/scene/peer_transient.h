// Internal: scenes written for the peer transient renderers, mitransient (Mitsuba 3 based) and
// mitsuba2-transient (Mitsuba 2 based), rewritten into femto's own plugins before anything is
// built (docs/compatibility.md, "Peer transient renderers").
#pragma once

#include <vector>

#include "xml/parser.h"

namespace femto::detail {

/// Rewrites the peers' films (`transient_hdr_film`, `streakhdrfilm`) into femto's `transient`
/// film and their integrators (`transient_path` next to a `transient_hdr_film`,
/// `transient_prbvolpath`, `transientpath`) into femto's `transient_path`, checking every
/// parameter under the peer's name (located SceneErrors). Objects of femto's own scenes are left
/// alone. Returns the elements that are only to be checked by building them: the time filters of
/// `streakhdrfilm`, which mitsuba2-transient reads but never applies. Under `lenient`, a
/// parameter the peer does not know is a warning and dropped, as femto's unknown parameters are.
std::vector<XmlNode> translate_peer_transient(XmlNode& root, bool lenient);

}  // namespace femto::detail
