// Helpers for tests that build scenes from XML text.
#pragma once

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "femto/error.h"
#include "femto/host.h"
#include "femto/testing/render.h"

namespace femto::test {

using femto::testing::temp_dir;

inline void write_text(const std::filesystem::path& path, const std::string& text) {
    std::ofstream out(path);
    out << text;
}

/// A minimal valid scene around `body` (a sensor with a small film is added unless `body`
/// has one).
inline std::string scene_xml(const std::string& body, const std::string& version = "3.0.0") {
    std::string s = "<scene version=\"" + version + "\">\n";
    if (body.find("<sensor") == std::string::npos)
        s += "<sensor type=\"perspective\"><film type=\"hdrfilm\"><integer name=\"width\" "
             "value=\"8\"/>"
             "<integer name=\"height\" value=\"8\"/></film></sensor>\n";
    return s + body + "\n</scene>\n";
}

inline const char* kRect = "<shape type=\"rectangle\"/>";

/// `v` with every digit a double holds, for numbers written into scene XML.
inline std::string xml_number(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.17g", v);
    return buf;
}

/// An `independent` sampler of `spp` samples per pixel.
inline std::string independent_sampler(int spp) {
    return "<sampler type=\"independent\"><integer name=\"sample_count\" value=\"" +
           std::to_string(spp) + "\"/></sampler>";
}

/// A `transient` film of w x h pixels and `bins` bins of `bin_width` from `start`, with a box
/// reconstruction filter (each pixel's samples its own) and the histogram in time.
inline std::string box_transient_film(int w, int h, double start, double bin_width, int bins) {
    return "<film type=\"transient\"><integer name=\"width\" value=\"" + std::to_string(w) +
           "\"/><integer name=\"height\" value=\"" + std::to_string(h) +
           "\"/><float name=\"start\" value=\"" + xml_number(start) +
           "\"/><float name=\"bin_width\" value=\"" + xml_number(bin_width) +
           "\"/><integer name=\"bins\" value=\"" + std::to_string(bins) +
           "\"/><rfilter type=\"box\"/><tfilter type=\"histogram\"/></film>";
}

/// Loads XML text and returns the SceneError's message (fails the test when none is thrown).
inline std::string load_error(const std::string& xml, const LoadOptions& options = {},
                              const std::string& base_dir = ".") {
    try {
        load_scene_string(xml, options, base_dir);
    } catch (const SceneError& e) {
        return e.what();
    }
    ADD_FAILURE() << "expected a SceneError for:\n" << xml;
    return {};
}

}  // namespace femto::test
