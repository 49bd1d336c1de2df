#include "scene/loader.h"

#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <new>
#include <set>

#include "femto/emitter.h"
#include "femto/integrator.h"
#include "femto/log.h"
#include "femto/sensor.h"
#include "femto/shape.h"
#include "plugin/registry.h"
#include "scene/instancing.h"
#include "scene/peer_transient.h"
#include "scene/spectrum_tags.h"
#include "util/lenient.h"
#include "util/strings.h"
#include "xml/parser.h"

namespace fs = std::filesystem;

namespace femto {

namespace detail {
namespace {

thread_local const LoadOptions* t_options = nullptr;
const LoadOptions kNoOptions{};

const LoadOptions& current_options() { return t_options ? *t_options : kNoOptions; }

struct OptionsScope {
    const LoadOptions* saved;
    explicit OptionsScope(const LoadOptions& o) : saved(t_options) { t_options = &o; }
    ~OptionsScope() { t_options = saved; }
};

const std::set<std::string> kPropertyTags = {"boolean",  "integer",   "float",    "string",
                                             "point",    "vector",    "rgb",      "srgb",
                                             "spectrum", "blackbody", "transform"};
const char* const kObjectTags =
    "integrator sensor film sampler rfilter tfilter shape bsdf emitter medium phase texture "
    "volume distance connection angular";

std::vector<double> parse_numbers(const XmlNode& node, const std::string& text, const char* what) {
    std::vector<double> out;
    const char* p = text.data();
    const char* end = p + text.size();
    while (p < end) {
        while (p < end && (std::isspace(static_cast<unsigned char>(*p)) || *p == ',')) ++p;
        if (p >= end) break;
        if (*p == '+') ++p;
        double v = 0;
        auto res = std::from_chars(p, end, v);
        if (res.ec != std::errc() ||
            (res.ptr < end && !std::isspace(static_cast<unsigned char>(*res.ptr)) &&
             *res.ptr != ','))
            throw SceneError(node.location,
                             fmt::format("{}: \"{}\" is not a number list", what, text));
        if (!std::isfinite(v))
            throw SceneError(node.location, fmt::format("{}: \"{}\" contains a non-finite number "
                                                        "(NaN or infinity)",
                                                        what, text));
        out.push_back(v);
        p = res.ptr;
    }
    return out;
}

double parse_number(const XmlNode& node, const std::string& text, const char* what) {
    auto v = parse_numbers(node, text, what);
    if (v.size() != 1)
        throw SceneError(node.location,
                         fmt::format("{}: expected one number, got \"{}\"", what, text));
    return v[0];
}

const std::string& require_attr(const XmlNode& node, const char* name) {
    const std::string* v = node.attribute(name);
    if (!v)
        throw SceneError(node.location,
                         fmt::format("<{}> needs the attribute \"{}\"", node.tag, name));
    return *v;
}

void check_attributes(const XmlNode& node, std::initializer_list<const char*> allowed) {
    for (const auto& a : node.attributes) {
        bool ok = false;
        for (const char* x : allowed) ok = ok || a.name == x;
        if (!ok) {
            std::vector<std::string> names(allowed.begin(), allowed.end());
            throw SceneError(node.location,
                             fmt::format("unknown attribute \"{}\" on <{}>{}; valid: {}", a.name,
                                         node.tag, did_you_mean(a.name, names), join(names)));
        }
    }
}

void check_no_children(const XmlNode& node) {
    if (!node.children.empty())
        throw SceneError(node.children[0].location,
                         fmt::format("<{}> cannot contain <{}>", node.tag, node.children[0].tag));
}

// Points, vectors and colours are single precision: a larger number would become infinite.
float to_float(const XmlNode& node, double v, const char* what) {
    constexpr double kFloatMax = std::numeric_limits<float>::max();
    if (std::abs(v) > kFloatMax)
        throw SceneError(node.location, fmt::format("{}: {:g} is beyond the range of single "
                                                    "precision (+-{:g})",
                                                    what, v, kFloatMax));
    return float(v);
}

Vec3 to_vec3(const XmlNode& node, const std::vector<double>& n, const char* what) {
    return {to_float(node, n[0], what), to_float(node, n[1], what), to_float(node, n[2], what)};
}

Vec3 parse_xyz(const XmlNode& node, float def) {
    if (const std::string* v = node.attribute("value")) {
        auto n = parse_numbers(node, *v, node.tag.c_str());
        if (n.size() == 1) return Vec3(to_float(node, n[0], node.tag.c_str()));
        if (n.size() != 3)
            throw SceneError(node.location,
                             fmt::format("<{}> value needs 1 or 3 numbers", node.tag));
        return to_vec3(node, n, node.tag.c_str());
    }
    Vec3 r(def);
    const char* axes[] = {"x", "y", "z"};
    for (int i = 0; i < 3; ++i)
        if (const std::string* a = node.attribute(axes[i]))
            r[i] = to_float(node, parse_number(node, *a, axes[i]), axes[i]);
    return r;
}

std::vector<double> parse_three_numbers(const XmlNode& node, const char* name) {
    auto n = parse_numbers(node, require_attr(node, name), name);
    if (n.size() != 3)
        throw SceneError(node.location, fmt::format("<{}> {} needs 3 numbers", node.tag, name));
    return n;
}

Vec3 parse_vec_attr(const XmlNode& node, const char* name) {
    return to_vec3(node, parse_three_numbers(node, name), name);
}

// A lookat's origin or target: a place in the scene, so within kMaxSceneCoordinate.
Vec3 parse_position_attr(const XmlNode& node, const char* name) {
    const auto n = parse_three_numbers(node, name);
    if (!within_scene_range(n[0], n[1], n[2]))
        throw SceneError(node.location, outside_scene_range(fmt::format("<{}> {}", node.tag, name),
                                                            n[0], n[1], n[2]));
    return to_vec3(node, n, name);
}

// Mitsuba lists a matrix's rows; femto's transforms are affine (a projective last row would
// make points divide by a varying w, which no shape, sensor or emitter expects).
Transform parse_matrix(const XmlNode& op) {
    check_attributes(op, {"value"});
    auto v = parse_numbers(op, require_attr(op, "value"), "matrix");
    Transform::Matrix mm{};
    if (v.size() == 16) {
        if (v[12] != 0 || v[13] != 0 || v[14] != 0 || v[15] != 1)
            throw SceneError(op.location,
                             fmt::format("<matrix> has the last row {:g} {:g} {:g} {:g}, not 0 0 "
                                         "0 1: femto's transforms are affine (no projection)",
                                         v[12], v[13], v[14], v[15]));
        for (int i = 0; i < 16; ++i) mm[i / 4][i % 4] = v[i];
    } else if (v.size() == 9) {
        for (int i = 0; i < 9; ++i) mm[i / 3][i % 3] = v[i];
        mm[3][3] = 1;
    } else {
        throw SceneError(op.location,
                         fmt::format("<matrix> needs 16 (or 9) numbers, got {}", v.size()));
    }
    return Transform(mm);
}

Transform parse_transform(const XmlNode& node) {
    Transform t;
    for (const auto& op : node.children) {
        check_no_children(op);
        try {
            Transform m;
            if (op.tag == "translate") {
                check_attributes(op, {"x", "y", "z", "value"});
                m = Transform::translate(parse_xyz(op, 0.f));
            } else if (op.tag == "scale") {
                check_attributes(op, {"x", "y", "z", "value"});
                m = Transform::scale(parse_xyz(op, 1.f));
            } else if (op.tag == "rotate") {
                check_attributes(op, {"x", "y", "z", "value", "axis", "angle"});
                Vec3 axis = op.attribute("axis") ? parse_vec_attr(op, "axis") : parse_xyz(op, 0.f);
                m = Transform::rotate(axis, parse_number(op, require_attr(op, "angle"), "angle"));
            } else if (op.tag == "lookat") {
                check_attributes(op, {"origin", "target", "up"});
                const Vec3 o = parse_position_attr(op, "origin");
                const Vec3 tg = parse_position_attr(op, "target");
                Vec3 up;
                if (op.attribute("up")) {
                    up = parse_vec_attr(op, "up");
                } else {  // any up perpendicular to the view direction
                    up = Frame(normalize(tg - o)).s;
                }
                m = Transform::look_at(o, tg, up);
            } else if (op.tag == "matrix") {
                m = parse_matrix(op);
            } else {
                throw SceneError(op.location,
                                 fmt::format("unknown transform operation <{}>; valid: "
                                             "translate, rotate, scale, lookat, matrix",
                                             op.tag));
            }
            t = m * t;  // document order: later operations apply after earlier ones
        } catch (const std::domain_error& e) {
            throw SceneError(op.location,
                             fmt::format("degenerate transform <{}>: {}", op.tag, e.what()));
        }
    }
    return t;
}

Color parse_color(const XmlNode& node) {
    const std::string& value = require_attr(node, "value");
    if (node.tag == "srgb" && !value.empty() && value[0] == '#') {
        if (value.size() != 7)
            throw SceneError(node.location,
                             fmt::format("srgb \"{}\" must look like #rrggbb", value));
        Color c;
        for (int i = 0; i < 3; ++i) {
            unsigned v = 0;
            auto r = std::from_chars(value.data() + 1 + 2 * i, value.data() + 3 + 2 * i, v, 16);
            if (r.ec != std::errc() || r.ptr != value.data() + 3 + 2 * i)
                throw SceneError(node.location,
                                 fmt::format("srgb \"{}\" is not a hex colour", value));
            c[i] = srgb_to_linear(float(v) / 255.f);
        }
        return c;
    }
    auto n = parse_numbers(node, value, node.tag.c_str());
    Color c;
    if (n.size() == 1)
        c = Color(to_float(node, n[0], node.tag.c_str()));
    else if (n.size() == 3)
        c = Color(to_float(node, n[0], node.tag.c_str()), to_float(node, n[1], node.tag.c_str()),
                  to_float(node, n[2], node.tag.c_str()));
    else
        throw SceneError(node.location,
                         fmt::format("<{}> needs 1 or 3 numbers, got {}", node.tag, n.size()));
    if (node.tag == "srgb")
        for (int i = 0; i < 3; ++i) c[i] = srgb_to_linear(c[i]);
    return c;
}

class Instantiator {
public:
    explicit Instantiator(const LoadOptions& options) : options_(options) {}

    // An object is built once: where it is written, or earlier when a reference needs it.
    ObjectPtr build(const XmlNode& node, PluginKind kind) {
        if (auto it = built_.find(&node); it != built_.end()) return it->second;
        check_attributes(node, {"type", "id", "name"});
        const std::string& type = require_attr(node, "type");
        if (building_.size() >= kMaxBuildDepth)
            throw SceneError(node.location,
                             fmt::format("objects and the references they follow nest more than "
                                         "{} levels deep",
                                         kMaxBuildDepth));
        building_.push_back(&node);
        Properties props(type, node.location);
        if (const std::string* id = node.attribute("id")) props.set_id(*id);
        int arg_index = 0;
        for (const auto& child : node.children) add_child(props, child, node.tag, arg_index);

        const PluginDescriptor* builtin = kind == PluginKind::Shape ? builtin_shape(type) : nullptr;
        const PluginDescriptor& desc =
            builtin ? *builtin : find_plugin(kind, type, options_.plugin_dirs, node.location);
        resolve_file_names(props, desc, node);
        check_schema(props, desc, node);
        ObjectPtr obj = construct(desc, props, node);
        report_unread(props, node);
        building_.pop_back();
        built_.emplace(&node, obj);
        return obj;
    }

    ObjectPtr construct(const PluginDescriptor& desc, const Properties& props,
                        const XmlNode& node) {
        const std::string what = fmt::format("<{} type=\"{}\">", node.tag, desc.type_name);
        Object* raw = nullptr;
        try {
            raw = desc.create(props);
        } catch (const SceneError&) {
            throw;
        } catch (const std::bad_alloc&) {
            throw SceneError(node.location, what + ": out of memory (are the sizes sensible?)");
        } catch (const std::exception& e) {
            throw SceneError(node.location, what + ": " + e.what());
        }
        ObjectPtr obj(raw);
        obj->set_id(props.id());
        obj->set_type_name(desc.type_name);
        obj->set_location(props.location());
        return obj;
    }

    void check_schema(Properties& props, const PluginDescriptor& desc, const XmlNode& node) {
        std::vector<std::string> names;
        for (const auto& p : desc.params) {
            if (std::string(p.name) == "*") return;
            names.push_back(p.name);
        }
        for (const auto& e : props.entries()) {
            if (e.name.rfind("_arg_", 0) == 0) continue;
            if (auto it = std::find(names.begin(), names.end(), e.name); it != names.end()) {
                if (e.type == Properties::Type::Object)
                    check_object_fits(e, desc.params[size_t(it - names.begin())], desc, node);
                continue;
            }
            const std::string msg = fmt::format(
                "<{} type=\"{}\"> has no parameter \"{}\"{}; valid: {}", node.tag, desc.type_name,
                e.name, did_you_mean(e.name, names), names.empty() ? "(none)" : join(names));
            reject_unless_lenient(options_.lenient, e.location, msg);
            e.read = true;  // reported already; the plugin never sees it read
        }
    }

    // A schema type lists the alternatives a parameter takes: "color|texture", "filename|volume".
    static bool takes(const ParamSpec& spec, const char* alternative) {
        const std::string types = spec.type;
        size_t begin = 0;
        while (begin <= types.size()) {
            const size_t end = std::min(types.find('|', begin), types.size());
            if (types.compare(begin, end - begin, alternative) == 0) return true;
            begin = end + 1;
        }
        return false;
    }

    // Every <string> parameter the schema declares a "filename" is a file the plugin reads: it is
    // looked up here, next to the file that names it (an <include>d file's folder, then the
    // <path>s and the top-level scene's folder), so that no plugin resolves names itself and a
    // file found nowhere is an error at the element that names it.
    void resolve_file_names(Properties& props, const PluginDescriptor& desc,
                            const XmlNode& node) const {
        for (const auto& c : node.children) {
            const std::string* name = c.attribute("name");
            const std::string* value = c.attribute("value");
            if (c.tag != "string" || !name || !value || value->empty()) continue;
            for (const ParamSpec& spec : desc.params)
                if (*name == spec.name && takes(spec, "filename")) {
                    props.set(*name, Properties::Type::String, find_input_file(c, *value),
                              c.location);
                    break;
                }
        }
    }

    // An object's name is the parameter it binds to, so the parameter must take an object of
    // its kind ("color|texture" takes a <texture>, "film" a <film>).
    static void check_object_fits(const Properties::Entry& e, const ParamSpec& spec,
                                  const PluginDescriptor& desc, const XmlNode& node) {
        const ObjectPtr& obj = std::get<ObjectPtr>(e.value);
        if (!obj || takes(spec, kind_tag(obj->kind()))) return;
        const std::string types = spec.type;
        throw SceneError(
            e.location, fmt::format("<{}> named \"{}\": parameter \"{}\" of <{} type=\"{}\"> "
                                    "takes {}, not a <{}> (an object's name is the parameter "
                                    "it binds to)",
                                    kind_tag(obj->kind()), e.name, e.name, node.tag, desc.type_name,
                                    types, kind_tag(obj->kind())));
    }

    void report_unread(const Properties& props, const XmlNode& node) {
        for (const auto* e : props.unread()) {
            std::string msg;
            if (e->type == Properties::Type::Object)
                msg = fmt::format("<{} type=\"{}\"> does not use the nested object{}", node.tag,
                                  props.plugin_type(),
                                  e->name.rfind("_arg_", 0) == 0 ? "" : " \"" + e->name + "\"");
            else
                msg = fmt::format("<{} type=\"{}\"> did not use parameter \"{}\"", node.tag,
                                  props.plugin_type(), e->name);
            reject_unless_lenient(options_.lenient, e->location, msg);
        }
    }

    // A file a plugin reads: a name found nowhere is reported here, with the folders tried.
    std::string find_input_file(const XmlNode& c, const std::string& name) const {
        const FileSearch found = find_file(c, name, search_dirs_);
        if (!found.found && !found.searched.empty())
            throw SceneError(c.location, fmt::format("file \"{}\" not found (searched: {})", name,
                                                     join(found.searched)));
        return found.path;
    }

    // Every id of the scene, before anything is built: a reference may name an object
    // written after it (Mitsuba 3 resolves references once the whole file is read).
    void index_ids(const XmlNode& node) {
        for (const auto& c : node.children) {
            PluginKind kind;
            if (c.tag == "alias" && &node == root_) {
                check_attributes(c, {"id", "as"});
                check_no_children(c);
                add_id(require_attr(c, "as"), c, require_attr(c, "id"));
            } else if (kind_from_tag(c.tag, kind)) {
                if (const std::string* id = c.attribute("id")) add_id(*id, c, {});
                index_ids(c);
            }
        }
    }

    void add_id(const std::string& id, const XmlNode& node, const std::string& alias_of) {
        if (id.empty()) throw SceneError(node.location, "empty id");
        const auto [it, fresh] = ids_.emplace(id, IdTarget{&node, alias_of});
        if (!fresh)
            throw SceneError(node.location, fmt::format("id \"{}\" is defined twice (first at {})",
                                                        id, it->second.node->location.str()));
    }

    // The object `node` (a <ref> or an <alias>) names by its id, built now if need be.
    ObjectPtr resolve(const XmlNode& node) {
        std::string id = require_attr(node, "id");
        for (size_t hops = 0;; ++hops) {
            auto it = ids_.find(id);
            if (it == ids_.end()) {
                std::vector<std::string> known;
                for (const auto& [k, v] : ids_) known.push_back(k);
                throw SceneError(node.location,
                                 fmt::format("no object with id \"{}\" is defined in the "
                                             "scene{}",
                                             id, did_you_mean(id, known)));
            }
            const IdTarget& target = it->second;
            if (target.alias_of.empty()) {
                PluginKind kind;
                kind_from_tag(target.node->tag, kind);
                refuse_cycle(*target.node, id, node);
                return build(*target.node, kind);
            }
            if (hops > ids_.size())
                throw SceneError(node.location,
                                 fmt::format("the aliases of \"{}\" form a cycle", id));
            id = target.alias_of;
        }
    }

    // A reference to an object still being built (itself or one holding it) can never be
    // satisfied; the message lists the chain of ids.
    void refuse_cycle(const XmlNode& target, const std::string& id, const XmlNode& ref) const {
        auto it = std::find(building_.begin(), building_.end(), &target);
        if (it == building_.end()) return;
        std::string chain;
        for (; it != building_.end(); ++it)
            if (const std::string* i = (*it)->attribute("id"))
                chain += fmt::format("\"{}\" ({}) -> ", *i, (*it)->location.str());
        throw SceneError(ref.location,
                         fmt::format("reference cycle: {}\"{}\": an object cannot contain "
                                     "itself",
                                     chain, id));
    }

    // A name given twice in one object is a mistake whichever value was meant (Mitsuba 3
    // refuses it too), so it is not silently resolved to the last one.
    static void refuse_duplicate(const Properties& props, const std::string& name,
                                 const XmlNode& c) {
        if (props.has(name))
            throw SceneError(c.location,
                             fmt::format("\"{}\": parameter \"{}\" is given twice (first at {})",
                                         props.plugin_type(), name, props.location_of(name).str()));
    }

    void add_object(Properties& props, const XmlNode& c, ObjectPtr obj, int& arg_index) {
        const std::string* name = c.attribute("name");
        if (name) refuse_duplicate(props, *name, c);
        props.set_object(name ? *name : fmt::format("_arg_{}", arg_index++), std::move(obj),
                         c.location);
    }

    void add_child(Properties& props, const XmlNode& c, const std::string& parent_tag,
                   int& arg_index) {
        PluginKind kind;
        if (kind_from_tag(c.tag, kind)) {
            add_object(props, c, build(c, kind), arg_index);
            return;
        }
        if (c.tag == "ref") {
            check_attributes(c, {"id", "name"});
            check_no_children(c);
            add_object(props, c, resolve(c), arg_index);
            return;
        }
        if (!kPropertyTags.count(c.tag))
            throw SceneError(
                c.location,
                fmt::format("unknown tag <{}> inside <{}>; valid: {} ref {}", c.tag,
                            props.plugin_type().empty() ? "?" : props.plugin_type(),
                            join({kPropertyTags.begin(), kPropertyTags.end()}, " "), kObjectTags));
        const std::string& name = require_attr(c, "name");
        if (name.empty()) throw SceneError(c.location, "empty parameter name");
        refuse_duplicate(props, name, c);
        if (c.tag == "spectrum" || c.tag == "blackbody") {
            // Converted here: how a spectrum becomes RGB depends on the object it is in.
            props.set(name, Properties::Type::Color,
                      parse_spectrum_tag(c, parent_tag, name, search_dirs_), c.location);
            return;
        }
        if (c.tag != "transform") check_no_children(c);
        if (c.tag == "boolean") {
            check_attributes(c, {"name", "value"});
            std::string v = require_attr(c, "value");
            for (auto& ch : v) ch = char(std::tolower(static_cast<unsigned char>(ch)));
            if (v != "true" && v != "false")
                throw SceneError(c.location,
                                 fmt::format("boolean \"{}\" must be true or false, not \"{}\"",
                                             name, require_attr(c, "value")));
            props.set(name, Properties::Type::Bool, v == "true", c.location);
        } else if (c.tag == "integer") {
            check_attributes(c, {"name", "value"});
            const std::string& v = require_attr(c, "value");
            int64_t x = 0;
            const char* b = v.data();
            if (!v.empty() && v[0] == '+') ++b;
            auto r = std::from_chars(b, v.data() + v.size(), x);
            if (r.ec != std::errc() || r.ptr != v.data() + v.size())
                throw SceneError(
                    c.location,
                    fmt::format("integer \"{}\": \"{}\" is not an integer{}", name, v,
                                r.ec == std::errc::result_out_of_range ? " (out of range)" : ""));
            props.set(name, Properties::Type::Integer, x, c.location);
        } else if (c.tag == "float") {
            check_attributes(c, {"name", "value"});
            props.set(name, Properties::Type::Float,
                      parse_number(c, require_attr(c, "value"), name.c_str()), c.location);
        } else if (c.tag == "string") {
            check_attributes(c, {"name", "value"});
            props.set(name, Properties::Type::String, require_attr(c, "value"), c.location);
        } else if (c.tag == "point" || c.tag == "vector") {
            check_attributes(c, {"name", "value", "x", "y", "z"});
            props.set(name, c.tag == "point" ? Properties::Type::Point : Properties::Type::Vector,
                      parse_xyz(c, 0.f), c.location);
        } else if (c.tag == "rgb" || c.tag == "srgb") {
            check_attributes(c, {"name", "value"});
            props.set(name, Properties::Type::Color, parse_color(c), c.location);
        } else if (c.tag == "transform") {
            check_attributes(c, {"name"});
            props.set(name, Properties::Type::Transform, parse_transform(c), c.location);
        }
    }

    /// `checked`: elements built only to check them (translate_peer_transient()).
    std::unique_ptr<Scene> build_scene(const XmlNode& root, const std::vector<XmlNode>& checked) {
        check_attributes(root, {"version"});
        search_dirs_ = root.search_dirs;
        std::shared_ptr<Integrator> integrator;
        std::shared_ptr<Sensor> sensor;
        std::vector<std::shared_ptr<Shape>> shapes;
        std::vector<std::shared_ptr<Emitter>> emitters;
        root_ = &root;
        index_ids(root);
        // Before the objects they were taken from: their errors come first, before a film
        // allocates its cube.
        for (const XmlNode& c : checked) {
            PluginKind kind;
            if (kind_from_tag(c.tag, kind)) build(c, kind);
        }
        Properties scene_props("scene", root.location);
        std::map<std::string, SourceLocation> object_names;
        int arg_index = 0;
        for (const auto& c : root.children) {
            if (c.tag == "alias") {
                resolve(c);  // the object it names must exist
                continue;
            }
            if (kPropertyTags.count(c.tag)) {
                add_child(scene_props, c, root.tag, arg_index);
                continue;
            }
            PluginKind kind;
            if (!kind_from_tag(c.tag, kind))
                throw SceneError(c.location,
                                 fmt::format("unknown tag <{}> in <scene>; valid: {} alias path "
                                             "and the property tags",
                                             c.tag, kObjectTags));
            // Mitsuba 3 keys the scene's children by name: a name is accepted (it has no
            // meaning for femto's scene) but must be unique, as Mitsuba requires.
            if (const std::string* name = c.attribute("name")) {
                if (name->empty()) throw SceneError(c.location, "empty name");
                const auto [it, fresh] = object_names.emplace(*name, c.location);
                if (!fresh)
                    throw SceneError(c.location,
                                     fmt::format("name \"{}\" is given to two objects of the "
                                                 "scene (first at {})",
                                                 *name, it->second.str()));
            }
            ObjectPtr obj = build(c, kind);
            switch (kind) {
                case PluginKind::Integrator:
                    if (integrator)
                        throw SceneError(c.location, "the scene has more than one <integrator>");
                    integrator = std::static_pointer_cast<Integrator>(obj);
                    break;
                case PluginKind::Sensor:
                    take_sensor(std::static_pointer_cast<Sensor>(obj), c.location, sensor);
                    if (sensor->needs_shape())
                        throw SceneError(c.location,
                                         fmt::format("<sensor type=\"{}\"> measures on a surface: "
                                                     "nest it in the <shape> it measures on",
                                                     sensor->type_name()));
                    break;
                case PluginKind::Shape:
                    if (dynamic_cast<const ShapeGroup*>(obj.get()))
                        break;  // rendered only where instances place it
                    shapes.push_back(std::static_pointer_cast<Shape>(obj));
                    if (auto nested = shapes.back()->sensor_ptr())
                        take_sensor(nested, nested->location(), sensor);
                    break;
                case PluginKind::Emitter:
                    emitters.push_back(std::static_pointer_cast<Emitter>(obj));
                    break;
                default:
                    if (!c.attribute("id"))
                        log_warning(
                            c.location,
                            fmt::format("top-level <{}> without an id can never be used", c.tag));
                    break;
            }
        }
        check_scene_properties(scene_props);
        if (!sensor) throw SceneError(root.location, "the scene has no <sensor>: add a camera");
        if (shapes.empty() && emitters.empty())
            throw SceneError(root.location, "the scene is empty: it has no shapes and no emitters");
        if (!integrator)
            integrator = std::static_pointer_cast<Integrator>(
                create_default(PluginKind::Integrator, "path", root.location));
        return std::make_unique<Scene>(integrator, sensor, std::move(shapes), std::move(emitters));
    }

    // The scene's one sensor, at the top level or nested in a shape (an irradiance meter).
    static void take_sensor(std::shared_ptr<Sensor> found, const SourceLocation& where,
                            std::shared_ptr<Sensor>& sensor) {
        if (sensor)
            throw SceneError(where, fmt::format("the scene has more than one <sensor> (femto "
                                                "renders one; the first is at {})",
                                                sensor->location().str()));
        sensor = std::move(found);
    }

    // Properties written directly in <scene>: Mitsuba's scene reads only the settings of its
    // acceleration structure (0.6 and 3's kd-tree, 3's Embree), which femto's own Embree BVH
    // has no use for. They are accepted with a note; any other name is an unknown parameter.
    void check_scene_properties(const Properties& props) const {
        static const std::map<std::string, Properties::Type> kKnown = {
            {"kd_intersection_cost", Properties::Type::Float},
            {"kd_traversal_cost", Properties::Type::Float},
            {"kd_empty_space_bonus", Properties::Type::Float},
            {"kd_stop_prims", Properties::Type::Integer},
            {"kd_max_depth", Properties::Type::Integer},
            {"kd_exact_primitive_threshold", Properties::Type::Integer},
            {"kd_min_max_bins", Properties::Type::Integer},
            {"kd_max_bad_refines", Properties::Type::Integer},
            {"kd_clip", Properties::Type::Bool},
            {"kd_retract", Properties::Type::Bool},
            {"kd_retract_bad_splits", Properties::Type::Bool},
            {"kd_parallel_build", Properties::Type::Bool},
            {"embree_use_robust_intersections", Properties::Type::Bool},
        };
        std::vector<std::string> names;
        for (const auto& [k, v] : kKnown) names.push_back(k);
        for (const auto& e : props.entries()) {
            auto it = kKnown.find(e.name);
            if (it == kKnown.end()) {
                reject_unless_lenient(
                    options_.lenient, e.location,
                    fmt::format("<scene> has no property \"{}\"{}; valid (Mitsuba's "
                                "acceleration settings, which femto ignores): {}",
                                e.name, did_you_mean(e.name, names), join(names)));
                continue;
            }
            const bool number =
                it->second == Properties::Type::Float && e.type == Properties::Type::Integer;
            if (e.type != it->second && !number)
                throw SceneError(
                    e.location,
                    fmt::format("scene property \"{}\" must be {}", e.name,
                                it->second == Properties::Type::Bool      ? "a <boolean>"
                                : it->second == Properties::Type::Integer ? "an <integer>"
                                                                          : "a <float>"));
            log_note(e.location, fmt::format("femto ignores scene property \"{}\" (it tunes "
                                             "Mitsuba's acceleration structure; femto builds "
                                             "an Embree BVH)",
                                             e.name));
        }
    }

private:
    // Bounds the recursion through nested objects and the references they follow, so that a
    // long chain of forward references cannot overflow the stack.
    static constexpr size_t kMaxBuildDepth = 1000;
    struct IdTarget {
        const XmlNode* node;   // the object, or the <alias>
        std::string alias_of;  // for an <alias>: the id it stands for
    };

    const LoadOptions& options_;
    const XmlNode* root_ = nullptr;
    std::map<std::string, IdTarget> ids_;
    std::map<const XmlNode*, ObjectPtr> built_;
    std::vector<const XmlNode*> building_;  // objects under construction, outermost first
    std::vector<std::string> search_dirs_;  // the scene's <path> folders
};

}  // namespace

ObjectPtr create_default(PluginKind kind, const std::string& type, const SourceLocation& loc) {
    const LoadOptions& options = current_options();
    const PluginDescriptor& desc = find_plugin(kind, type, options.plugin_dirs, loc);
    Properties props(type, loc);
    XmlNode node;
    node.tag = kind_tag(kind);
    node.location = loc;
    return Instantiator(options).construct(desc, props, node);
}

ObjectPtr create_with(PluginKind kind, const std::string& type, const Properties& props_in) {
    const LoadOptions& options = current_options();
    Properties props = props_in;
    XmlNode node;
    node.tag = kind_tag(kind);
    node.location = props.location();
    Instantiator inst(options);
    const PluginDescriptor& desc = find_plugin(kind, type, options.plugin_dirs, props.location());
    inst.check_schema(props, desc, node);
    ObjectPtr obj = inst.construct(desc, props, node);
    inst.report_unread(props, node);
    return obj;
}

}  // namespace detail

std::unique_ptr<Scene> load_scene(const std::string& path, const LoadOptions& options) {
    detail::OptionsScope scope(options);
    detail::XmlNode root = detail::parse_scene_file(path, options.defines, options.lenient);
    const std::vector<detail::XmlNode> checked =
        detail::translate_peer_transient(root, options.lenient);
    return detail::Instantiator(options).build_scene(root, checked);
}

std::unique_ptr<Scene> load_scene_string(const std::string& xml, const LoadOptions& options,
                                         const std::string& base_dir) {
    detail::OptionsScope scope(options);
    detail::XmlNode root =
        detail::parse_scene_string(xml, base_dir, options.defines, options.lenient);
    const std::vector<detail::XmlNode> checked =
        detail::translate_peer_transient(root, options.lenient);
    return detail::Instantiator(options).build_scene(root, checked);
}

ObjectPtr create_object(PluginKind kind, const std::string& type, const Properties& props,
                        const LoadOptions& options) {
    detail::OptionsScope scope(options);
    return detail::create_with(kind, type, props);
}

const PluginDescriptor& find_plugin(PluginKind kind, const std::string& type,
                                    const LoadOptions& options) {
    return detail::find_plugin(kind, type, options.plugin_dirs, SourceLocation{});
}

std::vector<std::pair<std::string, const PluginDescriptor*>> list_plugins(
    const LoadOptions& options) {
    return detail::list_plugins(options.plugin_dirs);
}

std::vector<std::string> loaded_plugin_files() { return detail::loaded_plugin_files(); }

std::vector<std::string> plugin_search_path(const LoadOptions& options) {
    return detail::plugin_search_path(options.plugin_dirs);
}

const char* version() { return FEMTO_VERSION; }

ObjectPtr create_default_object(PluginKind kind, const std::string& type,
                                const SourceLocation& loc) {
    return detail::create_default(kind, type, loc);
}

ObjectPtr create_child_object(PluginKind kind, const std::string& type, const Properties& props) {
    return detail::create_with(kind, type, props);
}

}  // namespace femto
