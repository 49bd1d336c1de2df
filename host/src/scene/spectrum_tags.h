// Internal: the spectrum tags of a scene file (<spectrum>, Mitsuba 0.6's <blackbody>) to
// linear RGB.
#pragma once

#include <string>
#include <vector>

#include "color/spectrum.h"
#include "femto/color.h"
#include "xml/parser.h"

namespace femto::detail {

/// How parameter `name` of an object written as <parent_tag> uses a spectrum: emission inside
/// <emitter>, unbounded for indices of refraction and media coefficients, else reflectance.
spectrum::Use spectrum_use(const std::string& parent_tag, const std::string& name);

/// The colour of a <spectrum> or <blackbody> element `node`, the parameter `name` of an
/// object written as <parent_tag>. A spectrum file is looked up as every input file
/// (find_file(): the <path> folders `search_dirs`, then next to the naming file). Bad input is
/// a SceneError located at the element (or at the line of a spectrum file).
Color parse_spectrum_tag(const XmlNode& node, const std::string& parent_tag,
                         const std::string& name, const std::vector<std::string>& search_dirs);

}  // namespace femto::detail
