// Internal: file:line:col of a byte offset in a text (for the XML readers' messages).
#pragma once

#include <algorithm>
#include <cstddef>
#include <string>
#include <vector>

#include "femto/error.h"

namespace femto::detail {

struct LineTable {
    std::vector<size_t> starts{0};
    explicit LineTable(const std::string& text) {
        for (size_t i = 0; i < text.size(); ++i)
            if (text[i] == '\n') starts.push_back(i + 1);
    }
    SourceLocation at(const std::string& file, ptrdiff_t offset) const {
        if (offset < 0) offset = 0;
        auto it = std::upper_bound(starts.begin(), starts.end(), size_t(offset));
        const size_t line = size_t(it - starts.begin());
        return {file, int(line), int(size_t(offset) - starts[line - 1] + 1)};
    }
};

}  // namespace femto::detail
