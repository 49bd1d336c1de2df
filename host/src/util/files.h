// Internal: whether a file name names anything, for messages.
#pragma once

#include <filesystem>
#include <system_error>

namespace femto::detail {

/// Whether `p` names a directory entry. An entry that cannot be followed (a symbolic link in a
/// loop or to nowhere, a folder on the way that cannot be read) counts as one, so that opening
/// it reports why (InputFile: "Too many levels of symbolic links", "a symbolic link to a file
/// that does not exist"), where std::filesystem::exists() says it is not there.
inline bool entry_exists(const std::filesystem::path& p) {
    std::error_code ec;
    const std::filesystem::file_status st = std::filesystem::symlink_status(p, ec);
    if (ec) return ec != std::errc::no_such_file_or_directory && ec != std::errc::not_a_directory;
    return st.type() != std::filesystem::file_type::not_found;
}

}  // namespace femto::detail
