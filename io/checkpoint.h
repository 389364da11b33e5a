// SPDX-License-Identifier: MIT
// pvsbake io: the checkpoint of a bake, the finished rows a killed bake leaves for the next run
// (docs/ALGORITHMS.md#resume, layout in docs/FORMAT.md#checkpoint).
//
// A folder beside the output, "<output>.checkpoint", of chunk files rows-000001.h5, rows-000002.h5, ...
// (under MPI, rank r > 0 writes rows-000001-r<r>.h5, ...).
// Each chunk is an HDF5 file written whole or not at all (io/atomic_file.h) and holds rows of a
// RowJournal (core/row_journal.h) with what they were made from: the tool version, the world's content hash
// and every parameter that can change a row (the bake's parameters outside run.*). A run reads only chunks
// made from the same three, so a row it finds is the row it would compute.
#pragma once

#include "core/row_journal.h"
#include "io/bake_file.h"

#include <cstdint>
#include <string>
#include <vector>

namespace pvs {

struct CheckpointIdentity {
    std::string tool_version;
    std::string world_hash;
    NamedStrings parameters;  // the bake's parameters outside run.*, in order
};

// "<output_path>.checkpoint".
std::string checkpoint_folder(const std::string& output_path);

// Does `folder` hold a chunk?
bool checkpoint_exists(const std::string& folder);

struct Checkpoint {
    std::vector<RowChunk> chunks;  // in the order they were written
    uint32_t next_index = 1;       // the number of the next chunk to write
};

// The chunks in `folder` (none when it does not exist). Throws pvs::Error (bad input) when a chunk was
// made by another tool version, from another world or with other parameters (naming the first difference),
// or cannot be read.
Checkpoint read_checkpoint(const std::string& folder, const CheckpointIdentity& expected);

// Writes chunk number `index` into `folder` (created when missing); `rank`: the MPI rank writing it (each
// rank numbers its own chunks). Throws pvs::Error (kIo) on failure and then leaves no partial chunk.
void write_checkpoint_chunk(const std::string& folder, uint32_t index, const CheckpointIdentity& id,
                            const RowChunk& chunk, int rank = 0);

// Removes the chunks (and chunks a killed write left half-written) and then the folder if it is empty.
// Never throws; returns false when something could not be removed.
bool remove_checkpoint(const std::string& folder);

}  // namespace pvs
