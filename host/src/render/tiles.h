// How the renderer cuts a film into tiles (internal; exposed for tests).
#pragma once

namespace femto {
class Film;
}

namespace femto::detail {

/// The side of the film's square tiles, in pixels: what a pass's threads share (it halves from
/// 32 until the film has enough tiles for many threads) and, for films whose blocks are as dense
/// as the film, what keeps the blocks small. Depends on the film alone, never on the thread
/// count.
int tile_size_for(const Film& film);

}  // namespace femto::detail
