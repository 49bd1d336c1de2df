#include "scene/spectrum_tags.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <charconv>
#include <cmath>
#include <string_view>
#include <vector>

#include "femto/input_file.h"
#include "femto/log.h"

namespace femto::detail {
namespace {

// Mitsuba 3 treats these names as unbounded spectra (src/core/xml.cpp); sigma_a and sigma_s
// are Mitsuba 0.6's medium coefficients, which femto's media still accept.
constexpr std::string_view kUnboundedNames[] = {"eta",     "k",       "int_ior", "ext_ior",
                                                "sigma_t", "sigma_a", "sigma_s"};
// A .spd file larger than this is not a spectrum (it would hold millions of samples).
constexpr uint64_t kMaxSpectrumFileBytes = 16u << 20;

bool is_separator(char c) { return c == ',' || std::isspace(static_cast<unsigned char>(c)); }

// Splits at whitespace and commas, as Mitsuba tokenizes spectrum values.
std::vector<std::string_view> tokenize(std::string_view text) {
    std::vector<std::string_view> out;
    size_t i = 0;
    while (i < text.size()) {
        while (i < text.size() && is_separator(text[i])) ++i;
        size_t j = i;
        while (j < text.size() && !is_separator(text[j])) ++j;
        if (j > i) out.push_back(text.substr(i, j - i));
        i = j;
    }
    return out;
}

// A whole token as a number; false when it is not one (from_chars rejects "nan" spelled
// with a sign, so NaN and infinity are caught by the finiteness check of the caller).
bool to_double(std::string_view s, double& v) {
    if (!s.empty() && s[0] == '+') s.remove_prefix(1);
    auto r = std::from_chars(s.data(), s.data() + s.size(), v);
    return r.ec == std::errc() && r.ptr == s.data() + s.size();
}

struct Samples {
    std::vector<double> nm, values;
};

Samples parse_pairs(const XmlNode& node, const std::string& text) {
    Samples s;
    for (std::string_view token : tokenize(text)) {
        const size_t colon = token.find(':');
        double nm = 0, v = 0;
        if (colon == std::string_view::npos || !to_double(token.substr(0, colon), nm) ||
            !to_double(token.substr(colon + 1), v))
            throw SceneError(node.location,
                             fmt::format("<spectrum> value: \"{}\" is not a wavelength:value pair "
                                         "(e.g. \"400:0.5, 500:0.6\")",
                                         token));
        s.nm.push_back(nm);
        s.values.push_back(v);
    }
    return s;
}

// Mitsuba 0.6's .spd files: one "wavelength value" pair per line, '#' starts a comment.
Samples read_spd_file(const XmlNode& node, const std::string& path) {
    InputFile file(path, node.location);
    if (file.size() > kMaxSpectrumFileBytes)
        throw SceneError(node.location,
                         fmt::format("spectrum file \"{}\" is {} bytes; a spectrum file is at "
                                     "most {} bytes",
                                     path, file.size(), kMaxSpectrumFileBytes));
    const std::string text = file.read_rest();
    Samples s;
    int line_no = 0;
    size_t start = 0;
    while (start < text.size()) {
        size_t end = text.find('\n', start);
        if (end == std::string::npos) end = text.size();
        std::string_view line(text.data() + start, end - start);
        start = end + 1;
        ++line_no;
        if (size_t hash = line.find('#'); hash != std::string_view::npos)
            line = line.substr(0, hash);
        const auto tokens = tokenize(line);
        if (tokens.empty()) continue;
        double nm = 0, v = 0;
        if (tokens.size() != 2 || !to_double(tokens[0], nm) || !to_double(tokens[1], v))
            throw SceneError(SourceLocation{path, line_no, 1},
                             fmt::format("expected \"wavelength value\" (two numbers), got \"{}\" "
                                         "(spectrum file named at {})",
                                         line, node.location.str()));
        s.nm.push_back(nm);
        s.values.push_back(v);
    }
    return s;
}

// Refuses a colour beyond single precision and warns when Mitsuba's clamp changed it.
void check_result(const XmlNode& node, const std::string& name, const spectrum::Conversion& c,
                  spectrum::Use use) {
    if (!c.rgb.is_finite())
        throw SceneError(node.location, fmt::format("spectrum \"{}\": its colour is beyond "
                                                    "the range of single precision",
                                                    name));
    if (!c.clamped) return;
    const auto rgb = spectrum::xyz_to_linear_srgb(c.xyz);
    log_warning(node.location,
                fmt::format("spectrum \"{}\": its colour ({:.4g}, {:.4g}, {:.4g}) is outside "
                            "sRGB{}; clamped to ({:.4g}, {:.4g}, {:.4g}) as Mitsuba 3 does",
                            name, rgb[0], rgb[1], rgb[2],
                            use == spectrum::Use::Reflectance ? " or above 1" : "", c.rgb.r,
                            c.rgb.g, c.rgb.b));
}

Color convert_samples(const XmlNode& node, const std::string& name, const Samples& s,
                      spectrum::Use use, const std::string& what) {
    if (const std::string problem = spectrum::sampled_problem(s.nm, s.values); !problem.empty())
        throw SceneError(node.location, fmt::format("{}: {}", what, problem));
    if (s.nm.back() < spectrum::kMinNm || s.nm.front() > spectrum::kMaxNm)
        log_warning(node.location,
                    fmt::format("spectrum \"{}\" lies outside 360-830 nm, the visible range "
                                "femto integrates over: it is black",
                                name));
    const auto c = spectrum::convert_sampled(s.nm, s.values, use);
    check_result(node, name, c, use);
    return c.rgb;
}

double parse_finite(const XmlNode& node, const char* attr, std::string_view text,
                    const char* what) {
    double v = 0;
    if (!to_double(text, v) || !std::isfinite(v))
        throw SceneError(node.location, fmt::format("<{}> {}: \"{}\" is not a finite number{}",
                                                    node.tag, attr, text, what));
    return v;
}

void check_attributes(const XmlNode& node, std::initializer_list<std::string_view> allowed) {
    for (const auto& a : node.attributes) {
        bool ok = false;
        for (auto x : allowed) ok = ok || a.name == x;
        if (!ok) {
            std::string names;
            for (auto x : allowed) names += (names.empty() ? "" : ", ") + std::string(x);
            throw SceneError(node.location, fmt::format("unknown attribute \"{}\" on <{}>; "
                                                        "valid: {}",
                                                        a.name, node.tag, names));
        }
    }
    if (!node.children.empty())
        throw SceneError(node.children[0].location,
                         fmt::format("<{}> cannot contain <{}>", node.tag, node.children[0].tag));
}

Color parse_blackbody(const XmlNode& node, const std::string& name, spectrum::Use use) {
    check_attributes(node, {"name", "temperature", "scale"});
    const std::string* t = node.attribute("temperature");
    if (!t) throw SceneError(node.location, "<blackbody> needs the attribute \"temperature\"");
    std::string_view text = *t;
    // Mitsuba 0.6 writes temperatures as "5000K".
    while (!text.empty() && std::isspace(static_cast<unsigned char>(text.back())))
        text.remove_suffix(1);
    if (!text.empty() && (text.back() == 'K' || text.back() == 'k')) text.remove_suffix(1);
    const double kelvin = parse_finite(node, "temperature", text, " (kelvin, e.g. \"5000K\")");
    if (kelvin <= 0)
        throw SceneError(node.location,
                         fmt::format("<blackbody> temperature must be positive, got {} K", kelvin));
    const std::string* s = node.attribute("scale");
    const double scale = s ? parse_finite(node, "scale", *s, "") : 1.0;
    const auto c =
        spectrum::convert([&](double nm) { return scale * spectrum::planck(nm, kelvin); },
                          spectrum::kMinNm, spectrum::kMaxNm, use);
    check_result(node, name, c, use);
    return c.rgb;
}

}  // namespace

spectrum::Use spectrum_use(const std::string& parent_tag, const std::string& name) {
    if (parent_tag == "emitter") return spectrum::Use::Emission;
    for (auto n : kUnboundedNames)
        if (name == n) return spectrum::Use::Unbounded;
    return spectrum::Use::Reflectance;
}

Color parse_spectrum_tag(const XmlNode& node, const std::string& parent_tag,
                         const std::string& name, const std::vector<std::string>& search_dirs) {
    const spectrum::Use use = spectrum_use(parent_tag, name);
    if (node.tag == "blackbody") return parse_blackbody(node, name, use);
    if (const std::string* type = node.attribute("type"))
        throw SceneError(node.location,
                         fmt::format("<spectrum type=\"{}\"> is not supported: femto renders RGB, "
                                     "and Mitsuba 3's RGB variants have no spectrum plugins "
                                     "(its blackbody is spectral-only); give <blackbody "
                                     "temperature=\"...\"/>, wavelength:value pairs or an rgb",
                                     *type));
    check_attributes(node, {"name", "value", "filename"});
    const std::string* value = node.attribute("value");
    const std::string* filename = node.attribute("filename");
    if (!value == !filename)
        throw SceneError(node.location,
                         "<spectrum> needs either a \"value\" or a \"filename\" attribute");
    if (filename) {
        if (filename->empty()) throw SceneError(node.location, "<spectrum> filename is empty");
        const FileSearch found = find_file(node, *filename, search_dirs);
        if (!found.found && !found.searched.empty())
            throw SceneError(node.location,
                             fmt::format("spectrum file \"{}\" not found (searched: {})", *filename,
                                         fmt::join(found.searched, ", ")));
        const std::string& path = found.path;
        return convert_samples(node, name, read_spd_file(node, path), use,
                               fmt::format("spectrum file \"{}\"", path));
    }
    const auto tokens = tokenize(*value);
    if (tokens.size() == 1 && tokens[0].find(':') == std::string_view::npos)
        return spectrum::convert_uniform(
            parse_finite(node, "value", tokens[0],
                         " (a <spectrum> value is one number or wavelength:value pairs)"),
            use);
    if (tokens.empty()) throw SceneError(node.location, "<spectrum> value is empty");
    if (value->find(':') == std::string::npos)
        throw SceneError(node.location,
                         fmt::format("<spectrum> value \"{}\": a spectrum is one number or "
                                     "wavelength:value pairs; for three channels use <rgb>",
                                     *value));
    return convert_samples(node, name, parse_pairs(node, *value), use, "<spectrum> value");
}

}  // namespace femto::detail
