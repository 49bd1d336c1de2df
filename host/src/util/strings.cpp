#include "util/strings.h"

#include <algorithm>
#include <cctype>

namespace femto::detail {

size_t edit_distance(const std::string& a, const std::string& b) {
    std::vector<size_t> prev(b.size() + 1), cur(b.size() + 1);
    for (size_t j = 0; j <= b.size(); ++j) prev[j] = j;
    for (size_t i = 1; i <= a.size(); ++i) {
        cur[0] = i;
        for (size_t j = 1; j <= b.size(); ++j) {
            const bool same = std::tolower(static_cast<unsigned char>(a[i - 1])) ==
                              std::tolower(static_cast<unsigned char>(b[j - 1]));
            cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (same ? 0 : 1)});
        }
        std::swap(prev, cur);
    }
    return prev[b.size()];
}

std::string closest_match(const std::string& name, const std::vector<std::string>& candidates) {
    if (name.empty()) return {};
    const std::string* best = nullptr;
    size_t best_d = ~size_t(0);
    for (const auto& c : candidates) {
        const size_t d = edit_distance(name, c);
        if (d < best_d) {
            best_d = d;
            best = &c;
        }
    }
    if (!best || best_d > std::max<size_t>(2, name.size() / 2)) return {};
    return *best;
}

std::string did_you_mean(const std::string& name, const std::vector<std::string>& candidates) {
    const std::string best = closest_match(name, candidates);
    return best.empty() ? std::string() : " (did you mean \"" + best + "\"?)";
}

std::string with_article(const std::string& noun) {
    const size_t first = noun.find_first_not_of("<\"`");
    const char c = first == std::string::npos
                       ? 'x'
                       : char(std::tolower(static_cast<unsigned char>(noun[first])));
    return (std::string("aeiou").find(c) != std::string::npos ? "an " : "a ") + noun;
}

std::string tag_with_article(PluginKind kind) {
    return with_article("<" + std::string(kind_tag(kind)) + ">");
}

std::vector<std::string> split(const std::string& text, char sep) {
    std::vector<std::string> out(1);
    for (const char c : text)
        if (c == sep)
            out.emplace_back();
        else
            out.back() += c;
    return out;
}

std::string join(const std::vector<std::string>& items, const std::string& sep) {
    std::string out;
    for (size_t i = 0; i < items.size(); ++i) {
        if (i) out += sep;
        out += items[i];
    }
    return out;
}

}  // namespace femto::detail
