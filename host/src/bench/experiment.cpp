// Reader of `femto bench` experiment files (XML, docs/bench.md). Every element and attribute
// is checked: an unknown one is an error at its line and column, as in scene files.
#include "bench/experiment.h"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <pugixml.hpp>
#include <set>
#include <sstream>

#include "femto/input_file.h"
#include "util/line_table.h"
#include "util/strings.h"

namespace fs = std::filesystem;

namespace femto::bench {

namespace {

constexpr size_t kMaxExperimentBytes = size_t(16) << 20;
constexpr uint32_t kMaxSpp = 1u << 30;

class Reader {
public:
    Reader(std::string file, const std::string& text) : file_(std::move(file)), lines_(text) {}

    SourceLocation at(ptrdiff_t offset) const { return lines_.at(file_, offset); }
    SourceLocation at(const pugi::xml_node& n) const { return at(n.offset_debug() - 1); }

    [[noreturn]] void fail(const pugi::xml_node& n, const std::string& message) const {
        throw SceneError(at(n), message);
    }

    void check_attributes(const pugi::xml_node& n,
                          std::initializer_list<const char*> allowed) const {
        for (const pugi::xml_attribute& a : n.attributes()) {
            const bool ok = std::any_of(allowed.begin(), allowed.end(),
                                        [&](const char* k) { return std::string(k) == a.name(); });
            if (!ok)
                fail(n, fmt::format("<{}> has no attribute \"{}\"; valid: {}", n.name(), a.name(),
                                    detail::join(
                                        std::vector<std::string>(allowed.begin(), allowed.end()))));
        }
    }

    std::string required(const pugi::xml_node& n, const char* name) const {
        const pugi::xml_attribute a = n.attribute(name);
        if (!a) fail(n, fmt::format("<{}> needs a \"{}\" attribute", n.name(), name));
        return a.value();
    }

    double number(const pugi::xml_node& n, const char* attr, const std::string& text) const {
        double v = 0;
        const char* end = text.data() + text.size();
        const auto [ptr, ec] = std::from_chars(text.data(), end, v);
        if (text.empty() || ec != std::errc() || ptr != end || !std::isfinite(v))
            fail(n, fmt::format("<{}> {}: \"{}\" is not a finite number", n.name(), attr, text));
        return v;
    }

    // A whitespace- or comma-separated list of numbers.
    std::vector<double> numbers(const pugi::xml_node& n, const char* attr) const {
        std::string text = required(n, attr);
        std::replace(text.begin(), text.end(), ',', ' ');
        std::istringstream in(text);
        std::vector<double> out;
        for (std::string word; in >> word;) out.push_back(number(n, attr, word));
        if (out.empty()) fail(n, fmt::format("<{}> {} is empty", n.name(), attr));
        return out;
    }

    uint64_t whole(const pugi::xml_node& n, const char* attr, double v, double lo,
                   double hi) const {
        if (!(v >= lo && v <= hi) || v != std::floor(v))
            fail(n, fmt::format("<{}> {}: {} is not a whole number from {} to {}", n.name(), attr,
                                v, lo, hi));
        return uint64_t(v);
    }

    // <define name="..." value="..."/> children of `n` (other children are the caller's).
    Defines defines(const pugi::xml_node& n) const {
        Defines out;
        for (const pugi::xml_node& c : n.children("define")) {
            check_attributes(c, {"name", "value"});
            out.emplace_back(required(c, "name"), required(c, "value"));
        }
        return out;
    }

    void only_children(const pugi::xml_node& n, std::initializer_list<const char*> allowed) const {
        for (const pugi::xml_node& c : n.children()) {
            if (c.type() != pugi::node_element) continue;
            const bool ok = std::any_of(allowed.begin(), allowed.end(),
                                        [&](const char* k) { return std::string(k) == c.name(); });
            if (!ok)
                fail(c, fmt::format("<{}> cannot hold <{}>{}", n.name(), c.name(),
                                    allowed.size()
                                        ? "; valid: " + detail::join(std::vector<std::string>(
                                                            allowed.begin(), allowed.end()))
                                        : std::string(" (it has no children)")));
        }
    }

    std::string resolve(const pugi::xml_node& n, const std::string& path, bool folder) const {
        fs::path p(path);
        if (p.is_relative()) p = fs::path(file_).parent_path() / p;
        std::error_code ec;
        const bool ok = folder ? fs::is_directory(p, ec) : fs::is_regular_file(p, ec);
        if (!ok)
            fail(n, fmt::format("{} \"{}\" does not exist (looked for {})",
                                folder ? "folder" : "file", path, p.string()));
        return p.lexically_normal().string();
    }

private:
    std::string file_;
    detail::LineTable lines_;
};

// Names go into CSV cells and cache file names: no separators, quotes or line breaks.
std::string checked_name(const Reader& r, const pugi::xml_node& n, const std::string& name) {
    if (name.empty()) r.fail(n, fmt::format("<{}> has an empty name", n.name()));
    if (name.find_first_of(",\"/\\\n\r&<>|") != std::string::npos)
        r.fail(n, fmt::format("<{}> name \"{}\": a name may not hold , \" / \\ & < > | or a line "
                              "break (it names CSV cells, files, report cells and plot labels)",
                              n.name(), name));
    return name;
}

void read_budgets(const Reader& r, const pugi::xml_node& n, Experiment& e) {
    r.check_attributes(n, {"spp", "seconds"});
    r.only_children(n, {});
    const bool spp = bool(n.attribute("spp")), seconds = bool(n.attribute("seconds"));
    if (spp == seconds) r.fail(n, "<budgets> needs either spp=\"...\" or seconds=\"...\"");
    if (spp)
        for (double v : r.numbers(n, "spp"))
            e.spp_budgets.push_back(uint32_t(r.whole(n, "spp", v, 1, kMaxSpp)));
    else
        for (double v : r.numbers(n, "seconds")) {
            if (!(v >= 0.01 && v <= 1e6))
                r.fail(n, fmt::format("<budgets> seconds: {} is not in [0.01, 1e6]", v));
            e.time_budgets.push_back(v);
        }
    // A budget given twice would run twice and count twice in the fits.
    const std::vector<std::string> labels = e.budget_labels();
    if (std::set<std::string>(labels.begin(), labels.end()).size() != labels.size() ||
        std::set<double>(e.time_budgets.begin(), e.time_budgets.end()).size() !=
            e.time_budgets.size())
        r.fail(n, "<budgets> lists a budget twice");
}

void read_reference(const Reader& r, const pugi::xml_node& n, Experiment& e) {
    r.check_attributes(n, {"file", "variant", "spp", "seed", "scene"});
    r.only_children(n, {});
    ReferenceSpec& ref = e.reference;
    ref.location = r.at(n);
    if (n.attribute("file")) {
        if (n.attribute("variant") || n.attribute("spp") || n.attribute("seed") ||
            n.attribute("scene"))
            r.fail(n,
                   "<reference> takes either file=\"...\" or variant=\"...\" spp=\"...\" "
                   "(seed=\"...\" scene=\"...\")");
        ref.file = r.resolve(n, n.attribute("file").value(), false);
        return;
    }
    ref.variant = r.required(n, "variant");
    ref.scene = n.attribute("scene").value();
    // Rendered in two halves of spp / 2 samples.
    ref.spp = uint32_t(r.whole(n, "spp", r.number(n, "spp", r.required(n, "spp")), 2, kMaxSpp));
    if (n.attribute("seed"))
        ref.seed = r.whole(n, "seed", r.number(n, "seed", n.attribute("seed").value()), 0, 1e15);
    else
        ref.seed = 1000003;  // apart from the runs' seeds (1, 2, ...)
}

void read_child(const Reader& r, const pugi::xml_node& c, Experiment& e) {
    const std::string tag = c.name();
    if (tag == "scene") {
        r.check_attributes(c, {"file", "name"});
        r.only_children(c, {"define"});
        SceneSpec s;
        s.file = r.resolve(c, r.required(c, "file"), false);
        s.name =
            checked_name(r, c,
                         c.attribute("name") ? c.attribute("name").value()
                                             : fs::path(s.file).parent_path().filename().string());
        s.defines = r.defines(c);
        s.location = r.at(c);
        e.scenes.push_back(std::move(s));
    } else if (tag == "variant") {
        r.check_attributes(c, {"name"});
        r.only_children(c, {"define", "plugin_dir"});
        Variant v;
        v.name = checked_name(r, c, r.required(c, "name"));
        v.defines = r.defines(c);
        for (const pugi::xml_node& d : c.children("plugin_dir")) {
            r.check_attributes(d, {"path"});
            v.plugin_dirs.push_back(r.resolve(d, r.required(d, "path"), true));
        }
        v.location = r.at(c);
        if (e.find_variant(v.name)) r.fail(c, fmt::format("two variants are named \"{}\"", v.name));
        e.variants.push_back(std::move(v));
    } else if (tag == "budgets") {
        if (!e.spp_budgets.empty() || !e.time_budgets.empty()) r.fail(c, "a second <budgets>");
        read_budgets(r, c, e);
    } else if (tag == "seeds") {
        if (!e.seeds.empty()) r.fail(c, "a second <seeds>");
        r.check_attributes(c, {"count", "values"});
        r.only_children(c, {});
        if (bool(c.attribute("count")) == bool(c.attribute("values")))
            r.fail(c, "<seeds> needs either count=\"N\" (seeds 1 ... N) or values=\"...\"");
        if (c.attribute("count")) {
            const uint64_t n =
                r.whole(c, "count", r.number(c, "count", c.attribute("count").value()), 1, 10000);
            for (uint64_t s = 1; s <= n; ++s) e.seeds.push_back(s);
        } else {
            for (double v : r.numbers(c, "values"))
                e.seeds.push_back(r.whole(c, "values", v, 0, 1e15));
            if (std::set<uint64_t>(e.seeds.begin(), e.seeds.end()).size() != e.seeds.size())
                r.fail(c, "<seeds> lists a seed twice");
        }
    } else if (tag == "reference") {
        if (!e.reference.location.file.empty()) r.fail(c, "a second <reference>");
        read_reference(r, c, e);
    } else if (tag == "window") {
        r.check_attributes(c, {"name", "start", "end"});
        r.only_children(c, {});
        Window w{checked_name(r, c, r.required(c, "name")),
                 r.number(c, "start", r.required(c, "start")),
                 r.number(c, "end", r.required(c, "end"))};
        if (!(w.end > w.start)) r.fail(c, "<window> needs start < end");
        for (const Window& o : e.windows)
            if (o.name == w.name) r.fail(c, fmt::format("two windows are named \"{}\"", w.name));
        e.windows.push_back(w);
    } else if (tag == "pixel") {
        r.check_attributes(c, {"name", "x", "y"});
        r.only_children(c, {});
        PixelSpec p{checked_name(r, c, r.required(c, "name")),
                    int(r.whole(c, "x", r.number(c, "x", r.required(c, "x")), 0, 1e6)),
                    int(r.whole(c, "y", r.number(c, "y", r.required(c, "y")), 0, 1e6)), r.at(c)};
        for (const PixelSpec& o : e.pixels)
            if (o.name == p.name) r.fail(c, fmt::format("two pixels are named \"{}\"", p.name));
        e.pixels.push_back(p);
    } else if (tag == "metric") {
        r.check_attributes(c, {"name"});
        r.only_children(c, {});
        const std::string name = r.required(c, "name");
        if (std::find(e.metrics.begin(), e.metrics.end(), name) != e.metrics.end())
            r.fail(c, fmt::format("<metric> \"{}\" is named twice", name));
        e.metrics.push_back(name);
    } else if (tag == "isolation") {
        if (c.previous_sibling("isolation")) r.fail(c, "a second <isolation>");
        r.check_attributes(c, {"value"});
        r.only_children(c, {});
        const std::string v = r.required(c, "value");
        if (v != "process" && v != "none")
            r.fail(c, fmt::format("<isolation> value \"{}\": valid: none (every run in this "
                                  "process), process (each run in a child process)",
                                  v));
        e.child_processes = v == "process";
    } else if (tag == "raw_rays") {
        if (e.raw_rays_seconds > 0) r.fail(c, "a second <raw_rays>");
        r.check_attributes(c, {"seconds"});
        r.only_children(c, {});
        e.raw_rays_seconds = 1;
        if (c.attribute("seconds")) {
            e.raw_rays_seconds = r.number(c, "seconds", c.attribute("seconds").value());
            if (!(e.raw_rays_seconds >= 0.01 && e.raw_rays_seconds <= 3600))
                r.fail(c, fmt::format("<raw_rays> seconds: {} is not in [0.01, 3600]",
                                      e.raw_rays_seconds));
        }
    } else if (tag == "threads") {
        if (e.threads > 0) r.fail(c, "a second <threads>");
        r.check_attributes(c, {"value"});
        r.only_children(c, {});
        e.threads = int(r.whole(c, "value", r.number(c, "value", r.required(c, "value")), 1, 4096));
    } else {
        r.fail(c,
               fmt::format(
                   "unknown element <{}> in <experiment>; valid: scene, variant, "
                   "budgets, seeds, reference, window, pixel, metric, isolation, raw_rays, threads",
                   tag));
    }
}

// Each <metric> names a measure a run has: without a reference there is none (the study then
// measures throughput and memory), and a window or pixel must be declared.
void check_metrics(const Reader& r, const pugi::xml_node& root, Experiment& e) {
    if (!e.has_reference()) {
        if (root.child("metric"))
            r.fail(root.child("metric"),
                   "<metric> needs a <reference> to measure the error against");
        if (!e.windows.empty() || !e.pixels.empty())
            r.fail(root.child("window") ? root.child("window") : root.child("pixel"),
                   "<window> and <pixel> measure errors: they need a <reference>");
        return;
    }
    if (e.metrics.empty()) e.metrics = {"relmse"};
    for (const pugi::xml_node& n : root.children("metric")) {
        const std::string m = n.attribute("name").value();
        bool known = m == "relmse" || m == "pixel_relmse" || m == "frame_relmse";
        for (const Window& w : e.windows) known = known || m == "window:" + w.name;
        for (const PixelSpec& p : e.pixels) known = known || m == "pixel:" + p.name;
        if (!known)
            r.fail(n, fmt::format("<metric> name \"{}\": valid: relmse, pixel_relmse, "
                                  "frame_relmse, window:NAME or pixel:NAME of a declared <window> "
                                  "or <pixel>",
                                  m));
    }
}

}  // namespace

const SceneSpec& Experiment::reference_scene(const SceneSpec& scene) const {
    for (const SceneSpec& s : scenes)
        if (!reference.scene.empty() && s.name == reference.scene) return s;
    return scene;
}

const Variant* Experiment::find_variant(const std::string& wanted) const {
    for (const Variant& v : variants)
        if (v.name == wanted) return &v;
    return nullptr;
}

std::vector<std::string> Experiment::budget_labels() const {
    std::vector<std::string> out;
    for (uint32_t s : spp_budgets) out.push_back(std::to_string(s));
    for (double s : time_budgets) out.push_back(fmt::format("{}", s));
    return out;
}

std::string digest_hex(const std::string& bytes) {
    uint64_t h = 1469598103934665603ull;
    for (const unsigned char c : bytes) h = (h ^ c) * 1099511628211ull;
    return fmt::format("{:016x}", h);
}

Experiment load_experiment(const std::string& path) {
    const std::string problem = input_file_problem(path);
    if (!problem.empty())
        throw SceneError(fmt::format("experiment file \"{}\" cannot be read ({})", path, problem));
    InputFile file(path, SourceLocation{});
    if (file.size() > kMaxExperimentBytes)
        throw SceneError(fmt::format("experiment file \"{}\" is larger than 16 MiB", path));
    const std::string text = file.read_rest();
    const Reader r(path, text);
    pugi::xml_document doc;
    const pugi::xml_parse_result parsed = doc.load_buffer(text.data(), text.size());
    if (!parsed)
        throw SceneError(r.at(parsed.offset),
                         fmt::format("malformed XML: {}", parsed.description()));
    const pugi::xml_node root = doc.document_element();
    if (std::string(root.name()) != "experiment")
        r.fail(root, fmt::format("the root element is <{}>, not <experiment>", root.name()));
    r.check_attributes(root, {"name"});
    Experiment e;
    e.file = path;
    // What the rows depend on: everything but the seeds and budgets, so that adding seeds or
    // budgets resumes (the rows already measured stay valid); whitespace and comments aside.
    std::ostringstream canonical;
    for (const pugi::xml_attribute& a : root.attributes())
        canonical << a.name() << '=' << a.value();
    for (const pugi::xml_node& c : root.children()) {
        const std::string tag = c.name();
        if (c.type() == pugi::node_element && tag != "seeds" && tag != "budgets")
            c.print(canonical, "", pugi::format_raw);
    }
    e.digest = digest_hex(canonical.str());
    e.name =
        root.attribute("name") ? root.attribute("name").value() : fs::path(path).stem().string();
    for (const pugi::xml_node& c : root.children())
        if (c.type() == pugi::node_element) read_child(r, c, e);
    const SourceLocation top = r.at(root);
    if (e.scenes.empty()) throw SceneError(top, "the experiment has no <scene>");
    if (e.variants.empty()) throw SceneError(top, "the experiment has no <variant>");
    if (e.spp_budgets.empty() && e.time_budgets.empty())
        throw SceneError(top, "the experiment has no <budgets>");
    if (e.seeds.empty()) e.seeds = {1};
    check_metrics(r, root, e);
    if (!e.reference.variant.empty() && !e.find_variant(e.reference.variant))
        throw SceneError(e.reference.location,
                         fmt::format("<reference> names variant \"{}\", which is not declared",
                                     e.reference.variant));
    if (!e.reference.variant.empty())
        for (const uint64_t seed : e.seeds)
            if (seed == e.reference.seed || seed == e.reference.seed + 1)
                throw SceneError(e.reference.location,
                                 fmt::format("run seed {} is one of the reference's two halves' "
                                             "seeds ({} and {}): its runs would not be "
                                             "independent of the reference",
                                             seed, e.reference.seed, e.reference.seed + 1));
    if (!e.reference.file.empty() && e.scenes.size() > 1)
        throw SceneError(e.reference.location,
                         "a reference file fits one scene; with several scenes, give "
                         "variant=\"...\" spp=\"...\" (rendered per scene)");
    std::set<std::string> names;
    for (const SceneSpec& s : e.scenes)
        if (!names.insert(s.name).second)
            throw SceneError(
                s.location, fmt::format("two scenes are named \"{}\" (give name=\"...\")", s.name));
    if (!e.reference.scene.empty() && !names.count(e.reference.scene))
        throw SceneError(e.reference.location,
                         fmt::format("<reference> names scene \"{}\", which is not declared",
                                     e.reference.scene));
    return e;
}

}  // namespace femto::bench
