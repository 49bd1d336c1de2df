// Combining the accumulators (femto/accumulator.h) of the processes of a distributed render
// into rank 0's, chunk by chunk, independent of the transport (the CLI's MPI driver passes
// MPI_Send/MPI_Recv; the tests pass copies).
#pragma once

#include <cstddef>
#include <functional>
#include <vector>

#include "femto/accumulator.h"

namespace femto {

/// Elements per chunk of accumulator `a` for a chunk of about `chunk_bytes`.
size_t chunk_elements(const Accumulator& a, size_t chunk_bytes);

/// Calls send(pointer, bytes) for every chunk of every accumulator, in the order
/// combine_accumulators() receives them.
void send_accumulators(const std::vector<Accumulator>& own, size_t chunk_bytes,
                       const std::function<void(const void* data, size_t bytes)>& send);

/// Rank 0's side: for every chunk of every accumulator of `own`, receives the chunk of ranks
/// 1, 2, ..., ranks - 1 in that order (receive(rank, buffer, bytes)) and combines them with
/// its own in double precision (Float32 totals are rounded once, at the end of the chunk), so
/// the result depends on the rank count only, never on timing. Holds one chunk of doubles and
/// one receive buffer at a time.
void combine_accumulators(const std::vector<Accumulator>& own, int ranks, size_t chunk_bytes,
                          const std::function<void(int rank, void* buffer, size_t bytes)>& receive);

}  // namespace femto
