// Scenes of the peer transient renderers, read unchanged (docs/compatibility.md, "Peer transient
// renderers"):
//   - mitransient (Mitsuba 3 based): film `transient_hdr_film`, integrators `transient_path`
//     and `transient_prbvolpath`. Its `transient_path` shares its name with femto's, so it is
//     recognised by its film: mitransient's integrators refuse any other film.
//   - mitsuba2-transient (Mitsuba 2 based): film `streakhdrfilm`, whose time filter is a second
//     <rfilter name="tfilter">, and integrator `transientpath`.
// Both measure time as optical path length in scene units from emission at 0, as femto does, so
// the window maps one to one. The rewrite works on the scene tree, before anything is built:
// each object becomes femto's `transient` film or `transient_path` integrator with the same
// meaning, every parameter is checked under the peer's name (a located error names what the
// user wrote) and what femto does differently is refused or said in a note. Plugins know
// nothing of the peers.
#include "scene/peer_transient.h"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <set>
#include <string>

#include "femto/log.h"
#include "util/lenient.h"
#include "util/strings.h"

namespace femto::detail {
namespace {

const char* const kMitransient = "mitransient";
const char* const kMitsuba2 = "mitsuba2-transient";

const std::set<std::string> kPropertyTags = {"boolean",  "integer",   "float",    "string",
                                             "point",    "vector",    "rgb",      "srgb",
                                             "spectrum", "blackbody", "transform"};

bool is_property(const XmlNode& n) { return kPropertyTags.count(n.tag) > 0; }

std::string name_of(const XmlNode& n) {
    const std::string* name = n.attribute("name");
    return name ? *name : std::string();
}

std::string type_of(const XmlNode& n) {
    const std::string* type = n.attribute("type");
    return type ? *type : std::string();
}

// How an object of a peer is named in messages: <film type="streakhdrfilm"> (mitsuba2-transient).
std::string what(const XmlNode& obj, const std::string& type, const char* peer) {
    return fmt::format("<{} type=\"{}\"> ({})", obj.tag, type, peer);
}

[[noreturn]] void fail(const XmlNode& at, const std::string& message) {
    throw SceneError(at.location, message);
}

// A parameter the peer's object does not read: an error naming the ones it does (under
// --lenient a warning, and the caller drops it).
thread_local bool t_lenient = false;
void unknown(const XmlNode& c, const std::string& object, const std::vector<std::string>& valid) {
    if (!is_property(c))
        return reject_unless_lenient(t_lenient, c.location,
                                     fmt::format("{} takes no nested <{}>", object, c.tag));
    const std::string name = name_of(c);
    reject_unless_lenient(t_lenient, c.location,
                          fmt::format("{} has no parameter \"{}\"{}; valid: {}", object, name,
                                      did_you_mean(name, valid), join(valid)));
}

const std::string& value_of(const XmlNode& c) {
    const std::string* v = c.attribute("value");
    if (!v) fail(c, fmt::format("<{}> \"{}\" needs a value", c.tag, name_of(c)));
    return *v;
}

void require_tag(const XmlNode& c, std::initializer_list<const char*> tags, const char* noun) {
    for (const char* t : tags)
        if (c.tag == t) return;
    fail(c, fmt::format("\"{}\" must be {}, not <{}>", name_of(c), noun, c.tag));
}

int64_t read_integer(const XmlNode& c) {
    require_tag(c, {"integer"}, "an <integer>");
    const std::string& v = value_of(c);
    int64_t x = 0;
    const char* b = v.data() + (!v.empty() && v[0] == '+' ? 1 : 0);
    const auto r = std::from_chars(b, v.data() + v.size(), x);
    if (r.ec != std::errc() || r.ptr != v.data() + v.size())
        fail(c, fmt::format("integer \"{}\": \"{}\" is not an integer", name_of(c), v));
    return x;
}

// A finite number, from a <float> or an <integer> (both are numbers to Mitsuba).
double read_number(const XmlNode& c) {
    require_tag(c, {"float", "integer"}, "a <float>");
    const std::string& v = value_of(c);
    char* end = nullptr;
    const double x = std::strtod(v.c_str(), &end);
    if (v.empty() || end != v.c_str() + v.size())
        fail(c, fmt::format("\"{}\": \"{}\" is not a number", name_of(c), v));
    if (!std::isfinite(x))
        fail(c, fmt::format("\"{}\" must be a finite number, not \"{}\"", name_of(c), v));
    return x;
}

bool read_boolean(const XmlNode& c) {
    require_tag(c, {"boolean"}, "a <boolean>");
    std::string v = value_of(c);
    for (auto& ch : v) ch = char(std::tolower(static_cast<unsigned char>(ch)));
    if (v != "true" && v != "false")
        fail(c, fmt::format("boolean \"{}\" must be true or false, not \"{}\"", name_of(c),
                            value_of(c)));
    return v == "true";
}

std::string read_string(const XmlNode& c) {
    require_tag(c, {"string"}, "a <string>");
    return value_of(c);
}

// A string parameter that must take one of `valid` (compared without case, as the peers do).
std::string read_choice(const XmlNode& c, const std::vector<std::string>& valid) {
    std::string v = read_string(c);
    for (auto& ch : v) ch = char(std::tolower(static_cast<unsigned char>(ch)));
    if (std::find(valid.begin(), valid.end(), v) == valid.end())
        fail(c, fmt::format("\"{}\" must be one of {}, not \"{}\"", name_of(c), join(valid),
                            value_of(c)));
    return v;
}

std::string number_text(double v) { return fmt::format("{:.17g}", v); }

// An element the rewrite adds, placed where `at` stands (errors point there).
XmlNode element(const char* tag, std::vector<XmlAttribute> attributes, const XmlNode& at) {
    XmlNode n;
    n.tag = tag;
    n.attributes = std::move(attributes);
    n.location = at.location;
    n.base_dir = at.base_dir;
    n.root_dir = at.root_dir;
    return n;
}

// A property element femto's plugins read, placed where `at` stands.
XmlNode property(const char* tag, const std::string& name, const std::string& value,
                 const XmlNode& at) {
    return element(tag, {{"name", name}, {"value", value}}, at);
}

// The peer's name for a parameter becomes femto's; the element keeps its place in the file.
XmlNode renamed(const XmlNode& c, const std::string& femto_name) {
    XmlNode n = c;
    *n.attribute("name") = femto_name;
    return n;
}

bool contains_tag(const XmlNode& node, const std::string& tag,
                  const std::set<std::string>& types = {}) {
    if (node.tag == tag && (types.empty() || types.count(type_of(node)))) return true;
    for (const auto& c : node.children)
        if (contains_tag(c, tag, types)) return true;
    return false;
}

// The peers' sensors take their film whatever its name (a scene may write
// <film type="streakhdrfilm" name="streakfilm">), while in femto a nested object's name is the
// parameter it binds to: the rewritten film is left unnamed, which femto's sensors take.
void drop_name(XmlNode& film) {
    std::erase_if(film.attributes, [](const XmlAttribute& a) { return a.name == "name"; });
}

void collect(XmlNode& node, const std::string& tag, const std::string& type,
             std::vector<XmlNode*>& out) {
    if (node.tag == tag && type_of(node) == type) out.push_back(&node);
    for (auto& c : node.children) collect(c, tag, type, out);
}

// Plugins of the peers that femto has no counterpart for: refused by name, with the reason.
struct Refused {
    const char* tag;
    const char* type;
    const char* reason;
};
constexpr Refused kRefused[] = {
    {"integrator", "transient_nlos_path",
     "mitransient's NLOS integrator (confocal and exhaustive relay-wall captures) has no femto "
     "counterpart"},
    {"integrator", "transient_stokes",
     "mitransient's polarised integrator (Stokes vectors) has no femto counterpart: femto renders "
     "unpolarised RGB"},
    {"sensor", "nlos_capture_meter",
     "mitransient's NLOS capture meter (a relay-wall sensor) has no femto counterpart"},
    {"film", "phasor_hdr_film",
     "mitransient's phasor film (frequency-domain storage) has no femto counterpart: use "
     "transient_hdr_film"},
};

void refuse_unsupported(const XmlNode& node) {
    for (const Refused& r : kRefused)
        if (node.tag == r.tag && type_of(node) == r.type)
            fail(node, fmt::format("<{} type=\"{}\">: {}", r.tag, r.type, r.reason));
    for (const auto& c : node.children) refuse_unsupported(c);
}

// ---------------------------------------------------------------------------------------------
// mitransient

// What a mitransient integrator decides about its film's time axis.
struct TimeAxis {
    bool camera_unwarp = false;
    XmlNode unwarp_at;  // where camera_unwarp was written
    std::string temporal_filter;
    XmlNode filter_at;
    // mitransient's default for the releases that applied the Gaussian filter.
    double gaussian_stddev = 2.0;
};

// The parameters every Mitsuba 3 sampling integrator reads and femto has no use for.
bool ignored_sampling_parameter(const XmlNode& c, const std::string& name) {
    if (name == "block_size" || name == "samples_per_pass") {
        read_integer(c);
        return true;
    }
    if (name == "timeout") {
        if (read_number(c) > 0)
            log_note(c.location, "femto ignores timeout (it renders every sample of the sampler)");
        return true;
    }
    return false;
}

// mitransient's transient_path (surfaces) or transient_prbvolpath (media): femto's
// transient_path with mitransient's defaults (max_depth 6 or -1, rr_depth 5).
TimeAxis translate_mitransient_integrator(XmlNode& integ, bool volumetric, bool has_media) {
    const std::string type = type_of(integ);
    const std::string object = what(integ, type, kMitransient);
    const std::vector<std::string> valid = {
        "max_depth",        "rr_depth",        "hide_emitters",        "camera_unwarp",
        "temporal_filter",  "gaussian_stddev", "discard_direct_light", "block_size",
        "samples_per_pass", "timeout"};
    TimeAxis axis;
    std::vector<XmlNode> kept;
    bool has_max_depth = false, has_rr_depth = false;
    for (const XmlNode& c : integ.children) {
        const std::string name = is_property(c) ? name_of(c) : std::string();
        if (name == "max_depth") {
            if (read_integer(c) < -1) fail(c, "max_depth must be -1 (infinite) or >= 0");
            has_max_depth = true;
            kept.push_back(c);
        } else if (name == "rr_depth") {
            // Mitsuba 3 refuses 0; femto would read it as "no roulette".
            if (read_integer(c) <= 0) fail(c, "rr_depth must be > 0 (as in Mitsuba 3)");
            has_rr_depth = true;
            kept.push_back(c);
        } else if (name == "hide_emitters") {
            read_boolean(c);
            kept.push_back(c);
        } else if (name == "camera_unwarp") {
            axis.camera_unwarp = read_boolean(c);
            axis.unwarp_at = c;
        } else if (name == "temporal_filter") {
            axis.temporal_filter = read_choice(c, {"", "box", "gaussian"});
            axis.filter_at = c;
        } else if (name == "gaussian_stddev") {
            axis.gaussian_stddev = read_number(c);
            if (!(axis.gaussian_stddev > 0)) fail(c, "gaussian_stddev must be > 0 (in bins)");
        } else if (name == "discard_direct_light") {
            if (read_boolean(c))
                fail(c,
                     "discard_direct_light=true is not supported: mitransient then drops the "
                     "emitters its paths hit at every depth while keeping the MIS weights "
                     "of light sampling, which femto's transient_path cannot reproduce");
        } else if (!ignored_sampling_parameter(c, name)) {
            unknown(c, object, valid);
        }
    }
    if (!has_max_depth)
        kept.push_back(property("integer", "max_depth", volumetric ? "-1" : "6", integ));
    if (!has_rr_depth) kept.push_back(property("integer", "rr_depth", "5", integ));
    integ.children = std::move(kept);
    *integ.attribute("type") = "transient_path";
    if (has_media && !volumetric)
        log_note(integ.location,
                 "the scene has media: femto's transient_path renders them, mitransient's "
                 "transient_path ignores them (transient_prbvolpath renders them)");
    if (has_media && volumetric && axis.camera_unwarp)
        log_note(axis.unwarp_at.location,
                 "camera_unwarp: femto removes the optical length to each camera path's first "
                 "scattering vertex (a surface or a point in a medium); mitransient's "
                 "transient_prbvolpath removes the length to the first surface that is not a "
                 "medium boundary. They differ where the camera looks into a medium");
    return axis;
}

// The film's time filter: mitransient's `gaussian` is a fixed Gaussian of gaussian_stddev bins
// (at least half a bin, as mitransient clamped it), which femto's kernel filter is with
// alpha = 1 (no shrinking); its Gaussian is truncated at 3 sigma, so bandwidth = 3 sigma.
XmlNode time_filter(const TimeAxis& axis, double bin_width, const XmlNode& film) {
    if (axis.temporal_filter != "gaussian")
        return element("tfilter", {{"type", "histogram"}}, film);
    const double sigma_bins = std::max(axis.gaussian_stddev, 0.5);
    XmlNode tf = element("tfilter", {{"type", "kernel"}}, axis.filter_at);
    tf.children = {
        property("string", "kernel", "gaussian", axis.filter_at),
        property("float", "alpha", "1", axis.filter_at),
        property("float", "bandwidth", number_text(3 * sigma_bins * bin_width), axis.filter_at)};
    log_note(axis.filter_at.location,
             fmt::format("temporal_filter=\"gaussian\": femto filters time with a Gaussian of "
                         "standard deviation {:g} bins truncated at 3 standard deviations (the "
                         "mitransient releases that applied it used Mitsuba's gaussian rfilter, "
                         "truncated at 4; current releases ignore temporal_filter)",
                         sigma_bins));
    return tf;
}

// Width and height pass through; a crop window femto cannot render is refused.
bool film_size_parameter(const XmlNode& c, const std::string& name, std::vector<XmlNode>& kept) {
    if (name == "width" || name == "height") {
        kept.push_back(c);
        return true;
    }
    if (name == "crop_offset_x" || name == "crop_offset_y" || name == "crop_width" ||
        name == "crop_height")
        fail(c, fmt::format("\"{}\": femto renders the whole film; crop windows are not "
                            "supported",
                            name));
    return false;
}

// mitransient's transient_hdr_film: femto's transient film (bins, bin_width, start) with the
// time axis its integrator chose.
void translate_transient_hdr_film(XmlNode& film, const TimeAxis& axis) {
    const std::string object = what(film, "transient_hdr_film", kMitransient);
    const std::vector<std::string> valid = {"width",         "height",     "temporal_bins",
                                            "bin_width_opl", "start_opl",  "crop_offset_x",
                                            "crop_offset_y", "crop_width", "crop_height",
                                            "sample_border", "rfilter"};
    std::vector<XmlNode> kept;
    bool has_bins = false, has_width = false;
    double bin_width = 0.003;  // mitransient's defaults: 2048 bins of 0.003
    for (const XmlNode& c : film.children) {
        if (c.tag == "rfilter" || c.tag == "ref") {  // Mitsuba 3 takes any nested rfilter
            kept.push_back(c);
            continue;
        }
        const std::string name = is_property(c) ? name_of(c) : std::string();
        if (film_size_parameter(c, name, kept)) continue;
        if (name == "temporal_bins") {
            if (read_integer(c) < 1) fail(c, "temporal_bins must be >= 1");
            kept.push_back(renamed(c, "bins"));
            has_bins = true;
        } else if (name == "bin_width_opl") {
            bin_width = read_number(c);
            if (!(bin_width > 0)) fail(c, "bin_width_opl must be > 0 (optical path length)");
            kept.push_back(renamed(c, "bin_width"));
            has_width = true;
        } else if (name == "start_opl") {
            read_number(c);
            kept.push_back(renamed(c, "start"));
        } else if (name == "sample_border") {
            if (read_boolean(c))
                log_note(c.location,
                         "femto ignores sample_border=true (camera samples stay "
                         "inside the film)");
        } else {
            unknown(c, object, valid);
        }
    }
    if (!has_bins) kept.push_back(property("integer", "bins", "2048", film));
    if (!has_width) kept.push_back(property("float", "bin_width", number_text(bin_width), film));
    if (axis.camera_unwarp)
        kept.push_back(property("boolean", "world_time", "true", axis.unwarp_at));
    kept.push_back(time_filter(axis, bin_width, film));
    film.children = std::move(kept);
    *film.attribute("type") = "transient";
    drop_name(film);
}

// ---------------------------------------------------------------------------------------------
// mitsuba2-transient

// mitsuba2-transient's transientpath: femto's transient_path without Russian roulette (the
// peer reads rr_depth but never plays roulette; the window ends its paths).
void translate_transientpath(XmlNode& integ, bool has_media, bool has_dielectric) {
    const std::string object = what(integ, "transientpath", kMitsuba2);
    const std::vector<std::string> valid = {"max_depth",
                                            "rr_depth",
                                            "hide_emitters",
                                            "filter_depth",
                                            "discard_direct_paths",
                                            "nlos_emitter_sampling",
                                            "block_size",
                                            "samples_per_pass",
                                            "timeout"};
    std::vector<XmlNode> kept;
    for (const XmlNode& c : integ.children) {
        const std::string name = is_property(c) ? name_of(c) : std::string();
        if (name == "max_depth") {
            if (read_integer(c) < -1) fail(c, "max_depth must be -1 (infinite) or >= 0");
            kept.push_back(c);
        } else if (name == "rr_depth") {
            if (read_integer(c) <= 0) fail(c, "rr_depth must be > 0 (as in Mitsuba 2)");
        } else if (name == "hide_emitters") {
            if (read_boolean(c))
                log_note(c.location,
                         "mitsuba2-transient's transientpath reads hide_emitters "
                         "but shows emitters anyway; femto does the same");
        } else if (name == "filter_depth") {
            read_integer(c);  // changes nothing in the peer either
        } else if (name == "discard_direct_paths" || name == "nlos_emitter_sampling") {
            if (read_boolean(c))
                fail(c, fmt::format("{}=true is not supported: it is mitsuba2-transient's NLOS "
                                    "setting, which femto's transient_path has no counterpart "
                                    "for",
                                    name));
        } else if (!ignored_sampling_parameter(c, name)) {
            unknown(c, object, valid);
        }
    }
    kept.push_back(property("integer", "rr_depth", "0", integ));
    integ.children = std::move(kept);
    *integ.attribute("type") = "transient_path";
    if (has_media)
        log_note(integ.location,
                 "the scene has media: femto's transient_path renders them, "
                 "mitsuba2-transient's transientpath ignores them");
    if (has_dielectric)
        log_note(integ.location,
                 "light refracted by a dielectric: femto counts optical length with the index "
                 "of the medium the light travels in; mitsuba2-transient's transientpath uses "
                 "the relative index of the last refraction (after leaving glass, 1/1.5 of the "
                 "length), so arrival times differ after such paths");
}

// One of streakhdrfilm's time parameters, under its name or the peer's older one.
struct TimeParameter {
    const char* name;
    const char* old_name;
    const char* femto_name;
};
constexpr TimeParameter kStreakTime[] = {{"num_bins", "time", "bins"},
                                         {"bin_width_opl", "exposure_time", "bin_width"},
                                         {"start_opl", "time_offset", "start"}};

// The streak film's output settings: checked as the peer checks them; femto always writes
// float RGB OpenEXR files where -o says.
bool streak_output_parameter(const XmlNode& c, const std::string& name) {
    if (name == "file_format") {
        if (read_choice(c, {"openexr", "exr", "rgbe", "pfm"}).find("exr") == std::string::npos)
            log_note(c.location, "femto writes OpenEXR whatever file_format says");
    } else if (name == "pixel_format") {
        const std::string v =
            read_choice(c, {"rgb", "rgba", "luminance", "luminance_alpha", "xyz", "xyza"});
        if (v != "rgb" && v != "rgba")
            fail(c, fmt::format("pixel_format \"{}\": femto writes RGB; use rgb or rgba", v));
    } else if (name == "component_format") {
        if (read_choice(c, {"float16", "float32", "uint32"}) != "float32")
            log_note(c.location, "femto writes float32 whatever component_format says");
    } else if (name == "filename") {
        log_note(c.location, "femto ignores the film's filename: outputs go where -o says");
        read_string(c);
    } else if (name == "banner") {
        read_boolean(c);  // Mitsuba 2 draws none either
    } else if (name == "auto_detect_bins") {
        if (read_boolean(c))
            fail(c,
                 "auto_detect_bins=true is not supported: femto's window is given, not "
                 "found by a pilot render; give start_opl and bin_width_opl");
    } else if (name == "high_quality_edges") {
        if (read_boolean(c))
            log_note(c.location,
                     "femto ignores high_quality_edges=true (camera samples stay "
                     "inside the film)");
    } else {
        return false;
    }
    return true;
}

// The rfilters of a streakhdrfilm: name="rfilter" filters space; name="tfilter" is read but never
// applied by the peer (its streak block bins by histogram), so femto bins by histogram too and
// only checks the element.
void streak_filter(const XmlNode& c, const std::string& object, std::vector<XmlNode>& kept,
                   std::vector<XmlNode>& checked) {
    const std::string name = name_of(c);
    if (name == "rfilter") {
        kept.push_back(c);
    } else if (name == "tfilter") {
        checked.push_back(c);
    } else {
        fail(c, fmt::format("{}: an <rfilter> is named \"rfilter\" (space) or \"tfilter\" "
                            "(time), not {}",
                            object, name.empty() ? "left unnamed" : "\"" + name + "\""));
    }
}

// mitsuba2-transient's streakhdrfilm records every row: femto's transient film (the x-y-t cube).
void translate_streakhdrfilm(XmlNode& film, std::vector<XmlNode>& checked) {
    const std::string object = what(film, "streakhdrfilm", kMitsuba2);
    std::vector<std::string> valid = {"width",
                                      "height",
                                      "crop_offset_x",
                                      "crop_offset_y",
                                      "crop_width",
                                      "crop_height",
                                      "high_quality_edges",
                                      "file_format",
                                      "pixel_format",
                                      "component_format",
                                      "filename",
                                      "banner",
                                      "auto_detect_bins",
                                      "rfilter"};
    for (const auto& t : kStreakTime) valid.insert(valid.end(), {t.name, t.old_name});
    std::vector<XmlNode> kept;
    const XmlNode* given[3] = {nullptr, nullptr, nullptr};
    for (const XmlNode& c : film.children) {
        if (c.tag == "rfilter" || c.tag == "ref") {
            streak_filter(c, object, kept, checked);
            continue;
        }
        const std::string name = is_property(c) ? name_of(c) : std::string();
        if (film_size_parameter(c, name, kept) || streak_output_parameter(c, name)) continue;
        bool time_parameter = false;
        for (int i = 0; i < 3; ++i) {
            const TimeParameter& t = kStreakTime[i];
            if (name != t.name && name != t.old_name) continue;
            if (given[i])
                fail(c, fmt::format("give {} or {}, not both (the other is at {})", t.name,
                                    t.old_name, given[i]->location.str()));
            given[i] = &c;
            time_parameter = true;
        }
        if (!time_parameter) unknown(c, object, valid);
    }
    // Checked under the peer's names; the defaults are Mitsuba 2's (1000 bins of 1 from 0).
    const char* defaults[3] = {"1000", "1", "0"};
    for (int i = 0; i < 3; ++i) {
        if (!given[i]) {
            kept.push_back(property(i == 0 ? "integer" : "float", kStreakTime[i].femto_name,
                                    defaults[i], film));
            continue;
        }
        const XmlNode& c = *given[i];
        const std::string name = name_of(c);
        if (i == 0 && read_integer(c) < 1) fail(c, name + " must be >= 1");
        if (i == 1 && !(read_number(c) > 0)) fail(c, name + " must be > 0 (optical path length)");
        if (i == 2) read_number(c);
        kept.push_back(renamed(c, kStreakTime[i].femto_name));
    }
    kept.push_back(element("tfilter", {{"type", "histogram"}}, film));
    film.children = std::move(kept);
    *film.attribute("type") = "transient";
    drop_name(film);
}

XmlNode* top_level_integrator(XmlNode& root) {
    for (auto& c : root.children)
        if (c.tag == "integrator") return &c;
    return nullptr;
}

}  // namespace

std::vector<XmlNode> translate_peer_transient(XmlNode& root, bool lenient) {
    t_lenient = lenient;
    refuse_unsupported(root);
    std::vector<XmlNode*> mi_films, m2_films;
    collect(root, "film", "transient_hdr_film", mi_films);
    collect(root, "film", "streakhdrfilm", m2_films);
    XmlNode* integ = top_level_integrator(root);
    const std::string integ_type = integ ? type_of(*integ) : std::string();
    const bool has_media = contains_tag(root, "medium");

    TimeAxis axis;
    const bool volumetric = integ_type == "transient_prbvolpath";
    if (volumetric || (integ_type == "transient_path" && !mi_films.empty())) {
        if (mi_films.empty())
            fail(*integ,
                 "mitransient's transient_prbvolpath renders into a transient_hdr_film "
                 "(mitransient refuses other films)");
        axis = translate_mitransient_integrator(*integ, volumetric, has_media);
    }
    for (XmlNode* film : mi_films) translate_transient_hdr_film(*film, axis);

    if (integ_type == "transientpath") {
        if (m2_films.empty())
            fail(*integ, "mitsuba2-transient's transientpath renders into a streakhdrfilm");
        translate_transientpath(*integ, has_media,
                                contains_tag(root, "bsdf", {"dielectric", "roughdielectric"}));
    }
    std::vector<XmlNode> checked;
    for (XmlNode* film : m2_films) translate_streakhdrfilm(*film, checked);
    return checked;
}

}  // namespace femto::detail
