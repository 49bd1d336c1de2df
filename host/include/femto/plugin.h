// femto public API: how a shared library declares the plugin it contains.
//
// A plugin library exports exactly one C symbol, `femto_plugin_descriptor`, returning a
// PluginDescriptor. Use FEMTO_PLUGIN below rather than writing it by hand:
//
// The schema lists the plugin's own parameters only: those its base classes read (a film's
// width and height, a shape's bsdf, ...) come from CLASS::inherited_params() and are put first.
// An own entry with an inherited name replaces it (to change its default or description).
//
//     class AmbientOcclusion : public femto::Integrator { ... };
//     FEMTO_PLUGIN(AmbientOcclusion, femto::PluginKind::Integrator, "ao",
//                  "Ambient occlusion (fraction of unoccluded hemisphere)",
//                  {{"samples", "integer", "16", "occlusion rays per camera sample"}})
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "femto/object.h"
#include "femto/properties.h"

namespace femto {

/// Bumped whenever a public header changes in a way that breaks compiled plugins.
/// (6: schemas carry the base classes' parameters, ParamSpec::inherited_from.)
/// (7: Object::location(); Film::block_bytes_per_pixel().)
/// (8: Hit::p_error; PathClock::travel_to() measures time between actual vertices.)
/// (9: splats and light paths: Integrator::source()/sample_light()/begin_pass(), SplatList,
///  Film::add_splat_weight(), Sensor::sample_direct(), Emitter::sample_emission().)
/// (10: shadow connections report their medium pieces (MediumPieces); SegmentDensities.)
/// (11: measurement sensors: Sensor::has_area()/ray_weight()/attach()/needs_shape(),
///  Shape::sensor_ptr(), ContributionList::scale(); films count refused contributions:
///  RejectedContributions, Film::rejected()/add_rejected(), TimeResolvedBlock::rejected().)
/// (15: file-name parameters are declared in the schema (type "filename", see ParamSpec) and
///  only those are resolved by the loader; Volume (femto/volume.h); create_child_object().)
/// (16: distant emitters: Emitter::is_infinite()/eval_environment()/pdf_environment()/
///  set_scene_sphere(), SceneSphere, Scene::sphere()/environment()/pdf_environment(),
///  PathClock::record_distant().)
/// (17: analytic cylinders: Shape::set_cylinder() and its members change Shape's layout.)
/// (18: integrator AOVs: Integrator::aov_names(), ContributionList::reset_aovs()/set_aov()/
///  aovs(), Film::prepare_aovs(); io::write_exr_rgb() takes extra named channels;
///  Bsdf::null_transmission(), trace_shadow()/connect_to_sensor() `through_masks`.)
/// (19: Hit::dpdu, the surface's u tangent, changes Hit's layout; Bsdf::reciprocal() and
///  eval_adjoint()/sample_adjoint() for paths traced from the lights.)
/// (20: ray differentials: Ray::differential, RayDifferential, Sensor::sample_differential(),
///  Hit::footprint (PixelFootprint).)
/// (21: the light's cone at a shading point: PixelFootprint::light_cone changes Hit's layout;
///  Emitter::subtended_half_angle(), Shape::subtended_half_angle().)
/// (22: adaptive sampling: Bsdf::adapts_sampling()/pixel_sample_share().)
/// (23: Bsdf::uses_footprint(): camera rays carry differentials only for such materials.)
/// (24: Bsdf::uses_tangent(): Hit::dpdu only for such materials; Shape's layout changes with
///  its lazily built area-sampling table.)
/// (25: distributed rendering: Film::accumulators(), Integrator::accumulators() (vtables),
///  femto/accumulator.h; TemporalFilter::prepare() takes the film's width and height.)
/// (26: a pilot in the image: Film::pilot_in_image(), Film::begin_pilot(bool),
///  TemporalFilter::pilot_in_image(), pilot_pixel() takes the pixel's sample count; PilotBlock's
///  layout.)
/// (27: RayDifferential::to_pixel_centre and PixelFootprint::to_pixel_centre change Ray's
///  differential and Hit's layout.)
/// (28: Sampler::dimension() and Sampler::advance_to() change Sampler's vtable.)
/// (29: DistanceSample::at changes the layout sample_distance() returns; DistanceMixture's
///  layout and MediumPieces::piece()'s result change.)
/// (30: ShapeSample::wi and ::distance change its layout, and a flag for flat vertex normals
///  Shape's; warp::AliasTable::sample() and warp::square_to_uniform_triangle() are inline, no
///  longer exported.)
inline constexpr uint32_t kPluginAbiVersion = 30;

struct PluginDescriptor {
    uint32_t abi_version;
    PluginKind kind;
    const char* type_name;
    const char* description;
    /// The base classes' parameters (CLASS::inherited_params()) merged with the plugin's own
    /// list by merge_params().
    std::vector<ParamSpec> params;
    /// Builds the object; throws SceneError on bad parameters.
    Object* (*create)(const Properties& props);
};

/// Builds plugin `type` of `kind` with default parameters, for a parent object whose child
/// was not given in the scene (e.g. a film's default <tfilter>). Throws SceneError.
ObjectPtr create_default_object(PluginKind kind, const std::string& type,
                                const SourceLocation& loc);

/// Builds plugin `type` of `kind` from `props`, checked against its schema as the loader checks
/// a scene's objects, for a parent that turns a shorthand parameter into the object it stands
/// for (a medium's density file name into a `gridvolume`). Throws SceneError.
ObjectPtr create_child_object(PluginKind kind, const std::string& type, const Properties& props);

}  // namespace femto

extern "C" {
typedef const femto::PluginDescriptor* (*femto_plugin_descriptor_fn)();
}

#define FEMTO_PLUGIN(CLASS, KIND, TYPE_NAME, DESCRIPTION, ...)                                  \
    extern "C" __attribute__((visibility("default"))) const femto::PluginDescriptor*            \
    femto_plugin_descriptor() {                                                                 \
        static const femto::PluginDescriptor descriptor{                                        \
            femto::kPluginAbiVersion,                                                           \
            KIND,                                                                               \
            TYPE_NAME,                                                                          \
            DESCRIPTION,                                                                        \
            femto::merge_params(CLASS::inherited_params(),                                      \
                                std::vector<femto::ParamSpec> __VA_ARGS__),                     \
            [](const femto::Properties& props) -> femto::Object* { return new CLASS(props); }}; \
        return &descriptor;                                                                     \
    }
