// Every plugin's schema against its constructor: each plugin found on the plugin path is built
// with default parameters (plus the few it cannot be built without), and the defaults its
// constructor used (Properties::defaults_used()) must be the ones its schema documents, and
// the reverse. A schema that documents a default the code does not use (or the other way
// round) fails here instead of misleading a user of `femto plugins NAME` or docs/plugins.md.
#include <gtest/gtest.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "btf/synth.h"
#include "femto/btf.h"
#include "femto/host.h"
#include "femto/plugin.h"
#include "femto/properties.h"
#include "vol_util.h"

namespace fs = std::filesystem;
using femto::PluginKind;
using femto::Properties;

namespace {

// Numbers of a default written as "0.5", "1e+30", "(0, 0, 1)" or "[1, 2]"; nothing when the
// text is not a list of numbers.
std::optional<std::vector<double>> numbers(std::string s) {
    for (char& c : s)
        if (c == '(' || c == ')' || c == '[' || c == ']' || c == ',') c = ' ';
    std::vector<double> out;
    const char* p = s.c_str();
    while (true) {
        while (*p == ' ') ++p;
        if (!*p) break;
        char* end = nullptr;
        const double v = std::strtod(p, &end);
        if (end == p || (*end && *end != ' ')) return std::nullopt;
        out.push_back(v);
        p = end;
    }
    if (out.empty()) return std::nullopt;
    return out;
}

// Same default? Numbers numerically (a grey colour "0.5" equals "(0.5, 0.5, 0.5)"), all else
// (booleans, strings, plugin types, "identity") exactly.
bool same_default(const std::string& schema, const std::string& used) {
    if (schema == used) return true;
    auto a = numbers(schema), b = numbers(used);
    if (!a || !b) return false;
    if (a->size() == 1 && b->size() == 3) a->resize(3, (*a)[0]);
    if (b->size() == 1 && a->size() == 3) b->resize(3, (*b)[0]);
    if (a->size() != b->size()) return false;
    for (size_t i = 0; i < a->size(); ++i) {
        const double x = (*a)[i], y = (*b)[i];
        if (std::abs(x - y) > 1e-6 * std::max({1.0, std::abs(x), std::abs(y)})) return false;
    }
    return true;
}

// A Mitsuba .serialized file (version 4, single precision) of one triangle.
void write_serialized_triangle(const fs::path& path) {
    std::string body;
    auto put = [&](const auto& v) { body.append(reinterpret_cast<const char*>(&v), sizeof v); };
    put(uint32_t(0x1000));
    body += '\0';  // the mesh's name
    put(uint64_t(3)), put(uint64_t(1));
    for (const float c : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f}) put(c);
    for (const uint32_t i : {0u, 1u, 2u}) put(i);
    uLongf size = compressBound(uLong(body.size()));
    std::string packed(size, '\0');
    compress(reinterpret_cast<Bytef*>(packed.data()), &size,
             reinterpret_cast<const Bytef*>(body.data()), uLong(body.size()));
    packed.resize(size);
    std::ofstream out(path, std::ios::binary);
    const uint16_t header[2] = {0x041C, 4};
    out.write(reinterpret_cast<const char*>(header), sizeof header);
    out.write(packed.data(), std::streamsize(packed.size()));
}

// Small input files for the plugins that read one.
struct Inputs {
    fs::path dir;
    Inputs() {
        dir = fs::temp_directory_path() / ("femto_schema_" + std::to_string(::getpid()));
        fs::create_directories(dir);
        std::ofstream(dir / "tri.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
        std::ofstream(dir / "tri.ply") << "ply\nformat ascii 1.0\nelement vertex 3\n"
                                          "property float x\nproperty float y\nproperty float z\n"
                                          "element face 1\nproperty list uchar int vertex_indices\n"
                                          "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
        std::ofstream(dir / "pixel.ppm", std::ios::binary) << "P6\n1 1\n255\n"
                                                           << std::string("\x80\x80\x80", 3);
        std::ofstream(dir / "env.ppm", std::ios::binary) << "P6\n2 3\n255\n"
                                                         << std::string(18, '\x40');
        write_serialized_triangle(dir / "tri.serialized");
        femto::btf::synth::Options btf;  // a small synthetic BTF (UBO2003's 81 directions)
        btf.width = btf.height = 2;
        btf.directions = femto::btf::ubo2003_directions();
        femto::btf::synth::write((dir / "tiny.bdi").string(), btf);
        femto::test::VolFile vol;
        vol.data = {1.f};
        femto::test::write_bytes(dir / "density.vol", vol.bytes());
    }
    ~Inputs() {
        std::error_code ec;
        fs::remove_all(dir, ec);
    }
    std::string operator()(const char* name) const { return (dir / name).string(); }
};

// What a plugin cannot be built without (parameters whose schema default is empty and that
// its constructor requires), by "<tag> type".
std::map<std::string, std::function<void(Properties&)>> required(const Inputs& in) {
    const auto time_window = [](Properties& p) {
        p.set_int("bins", 4);
        p.set_float("bin_width", 0.5);
    };
    // The meters measure one value: their film must have one pixel (and a box filter: the
    // irradiance meter picks its point on the shape by the film position).
    const auto one_pixel_film = [](Properties& p) {
        Properties film("hdrfilm", {});
        film.set_int("width", 1);
        film.set_int("height", 1);
        film.set_object("rfilter",
                        femto::create_default_object(PluginKind::ReconstructionFilter, "box", {}));
        p.set_object("film", femto::create_object(PluginKind::Film, "hdrfilm", film));
    };
    return {
        {"shape obj", [&](Properties& p) { p.set_string("filename", in("tri.obj")); }},
        {"shape ply", [&](Properties& p) { p.set_string("filename", in("tri.ply")); }},
        {"shape serialized",
         [&](Properties& p) { p.set_string("filename", in("tri.serialized")); }},
        {"texture bitmap", [&](Properties& p) { p.set_string("filename", in("pixel.ppm")); }},
        {"emitter envmap", [&](Properties& p) { p.set_string("filename", in("env.ppm")); }},
        {"bsdf btf", [&](Properties& p) { p.set_string("filename", in("tiny.bdi")); }},
        {"volume gridvolume", [&](Properties& p) { p.set_string("filename", in("density.vol")); }},
        {"emitter collimated", [](Properties& p) { p.set_float("radius", 1.0); }},
        {"film transient", time_window},
        {"film streak",
         [=](Properties& p) {
             time_window(p);
             p.set_int("row", 0);
         }},
        {"bsdf twosided",
         [](Properties& p) {
             p.set_object("bsdf", femto::create_default_object(PluginKind::Bsdf, "diffuse", {}));
         }},
        {"bsdf mask",
         [](Properties& p) {
             p.set_object("bsdf", femto::create_default_object(PluginKind::Bsdf, "diffuse", {}));
         }},
        {"integrator moment",
         [](Properties& p) {
             p.set_object("path", femto::create_default_object(PluginKind::Integrator, "path", {}));
         }},
        {"sensor radiancemeter", one_pixel_film},
        {"sensor irradiancemeter", one_pixel_film},
    };
}

// Schema defaults that are formulas, not values (the constructor computes them).
const std::set<std::string> kComputedDefaults = {
    "emitter spot: beam_width",  // "3/4 cutoff_angle"
};

// Known disagreements in files this change leaves alone; each must still disagree (remove it
// here when it is fixed, or the test fails to say so).
// Schema entries known to disagree with their constructors (none today).
const std::set<std::string> kKnownMismatches = {};

std::vector<std::string> check_plugin(const femto::PluginDescriptor& d, const Inputs& in) {
    const std::string key = std::string(femto::kind_tag(d.kind)) + " " + d.type_name;
    std::vector<std::string> problems;
    Properties props(d.type_name, {});
    const auto needs = required(in);
    if (auto it = needs.find(key); it != needs.end()) it->second(props);
    try {
        femto::ObjectPtr obj(d.create(props));
        if (!obj) return {key + ": the factory returned nothing"};
    } catch (const std::exception& e) {
        return {key + ": cannot be built with default parameters: " + e.what()};
    }
    std::map<std::string, const femto::ParamSpec*> schema;
    for (const femto::ParamSpec& p : d.params) schema[p.name] = &p;
    if (schema.count("*")) return {};  // forwards its parameters: nothing to compare

    std::set<std::string> used_names;
    for (const Properties::DefaultUse& u : props.defaults_used()) {
        used_names.insert(u.name);
        const std::string what = key + ": " + u.name;
        auto it = schema.find(u.name);
        if (it == schema.end())
            problems.push_back(what + ": the constructor used default \"" + u.value +
                               "\" for a parameter the schema does not list");
        else if (kComputedDefaults.count(what))
            problems.push_back(what + ": listed as a computed default, but the constructor used " +
                               "the value \"" + u.value + "\"");
        else if (!same_default(it->second->default_value, u.value))
            problems.push_back(what + ": the schema says default \"" + it->second->default_value +
                               "\", the constructor used \"" + u.value + "\"");
    }
    for (const femto::ParamSpec& p : d.params) {
        const std::string what = key + ": " + p.name;
        if (!*p.default_value || used_names.count(p.name) || props.has(p.name)) continue;
        if (kComputedDefaults.count(what)) {
            if (numbers(p.default_value))
                problems.push_back(what +
                                   ": listed as a computed default, but the schema gives "
                                   "the value \"" +
                                   std::string(p.default_value) + "\"");
            continue;
        }
        problems.push_back(what + ": the schema says default \"" + p.default_value +
                           "\", but the constructor did not use a default for it");
    }
    return problems;
}

}  // namespace

TEST(PluginSchemas, SameDefaultComparesNumbersNumerically) {
    EXPECT_TRUE(same_default("1e30", "1e+30"));
    EXPECT_TRUE(same_default("0.5", "0.5"));
    EXPECT_TRUE(same_default("0.5", "(0.5, 0.5, 0.5)"));
    EXPECT_TRUE(same_default("(0, 0, 1)", "(0, 0, 1)"));
    EXPECT_TRUE(same_default("10000", "10000"));
    EXPECT_FALSE(same_default("0.5", "0.25"));
    EXPECT_FALSE(same_default("(0, 0, 1)", "(0, 1, 0)"));
    EXPECT_FALSE(same_default("true", "false"));
    EXPECT_FALSE(same_default("bk7", "air"));
    EXPECT_FALSE(same_default("50mm", "50"));
}

TEST(PluginSchemas, PropertiesRecordTheDefaultsUsed) {
    Properties props("x", {});
    props.set_int("given", 3);
    props.get_int("given", 7);
    props.get_float("f", 1e30);
    props.get_bool("b", true);
    props.get_color("c", femto::Color(0.f, 0.f, 1.f));
    props.get_color("grey", femto::Color(0.5f));
    props.get_string("s", "bk7");
    props.get_transform("t", femto::Transform());
    std::vector<std::string> got;
    for (const auto& u : props.defaults_used()) got.push_back(u.name + "=" + u.value);
    EXPECT_EQ(got, (std::vector<std::string>{"f=1e+30", "b=true", "c=(0, 0, 1)", "grey=0.5",
                                             "s=bk7", "t=identity"}));
}

TEST(PluginSchemas, DefaultsMatchTheConstructors) {
    const Inputs in;
    const auto plugins = femto::list_plugins();
    std::set<PluginKind> kinds;
    std::vector<std::string> problems;
    for (const auto& [path, d] : plugins) {
        kinds.insert(d->kind);
        for (const std::string& p : check_plugin(*d, in)) problems.push_back(p);
    }
    // Every kind the build ships must have been checked.
    for (PluginKind k :
         {PluginKind::Integrator, PluginKind::Sensor, PluginKind::Film,
          PluginKind::ReconstructionFilter, PluginKind::TemporalFilter, PluginKind::Sampler,
          PluginKind::Shape, PluginKind::Bsdf, PluginKind::Emitter, PluginKind::Texture,
          PluginKind::Medium, PluginKind::Phase, PluginKind::Volume, PluginKind::Distance,
          PluginKind::Connection, PluginKind::Angular})
        EXPECT_TRUE(kinds.count(k)) << "no <" << femto::kind_tag(k) << "> plugin was found";

    std::set<std::string> known_seen;
    std::string report;
    for (const std::string& p : problems) {
        bool known = false;
        for (const std::string& k : kKnownMismatches)
            if (p.rfind(k + ":", 0) == 0) {
                known = true;
                known_seen.insert(k);
            }
        if (!known) report += "  " + p + "\n";
    }
    EXPECT_TRUE(report.empty()) << "schemas disagree with their constructors:\n" << report;
    for (const std::string& k : kKnownMismatches)
        EXPECT_TRUE(known_seen.count(k)) << "\"" << k << "\" agrees now: remove it from "
                                         << "kKnownMismatches";
}
