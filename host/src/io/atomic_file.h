// Internal (libfemto_io): atomic file writes. Write to temp_path_for(path), then
// commit_file(tmp, path) renames it into place, so a reader never sees a half-written file.
#pragma once

#include <string>

namespace femto::io::detail {

/// A unique temporary name in the destination folder, keeping the extension (OpenImageIO
/// picks the format from it).
std::string temp_path_for(const std::string& path);
/// Renames `tmp` to `path`; on failure removes `tmp` and throws SceneError.
void commit_file(const std::string& tmp, const std::string& path);

}  // namespace femto::io::detail
