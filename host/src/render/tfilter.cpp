// Shared parts of temporal reconstruction: the pilot pass and the base of the time-resolved
// films (which reads the <tfilter>).
#include "femto/tfilter.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "femto/log.h"
#include "femto/plugin.h"
#include "femto/properties.h"

namespace femto {

PilotBlock::PilotBlock(int x0, int y0, int w, int h, int film_width, bool world_time,
                       std::unique_ptr<FilmBlock> image)
    : x0_(x0),
      y0_(y0),
      w_(w),
      h_(h),
      film_width_(film_width),
      world_time_(world_time),
      arrivals_(size_t(w) * size_t(h)),
      samples_(size_t(w) * size_t(h), 0),
      image_(std::move(image)) {}

size_t PilotBlock::local_pixel(Vec2 pos) const {
    const int x = int(std::floor(pos.x)), y = int(std::floor(pos.y));
    if (x < x0_ || x >= x0_ + w_ || y < y0_ || y >= y0_ + h_) return SIZE_MAX;
    return size_t(y - y0_) * size_t(w_) + size_t(x - x0_);
}

void PilotBlock::put(Vec2 pos, const ContributionList& sample) {
    const size_t local = local_pixel(pos);
    if (local != SIZE_MAX && !sample.is_splat()) ++samples_[local];
    if (image_) {  // a pilot in the image: the sample waits for its pixel's bandwidth
        kept_samples_.push_back({pos, sample.sample_index(), uint32_t(kept_.size()),
                                 uint32_t(sample.items().size()), sample.sensor_distance(),
                                 sample.is_splat()});
        kept_.insert(kept_.end(), sample.items().begin(), sample.items().end());
        return;  // (its arrivals are read from what is kept, in deliver())
    }
    if (local != SIZE_MAX)
        add_arrivals(local, sample.items().data(), sample.items().size(), sample.sensor_distance());
}

void PilotBlock::add_arrivals(size_t local, const Contribution* first, size_t count,
                              double sensor_distance) const {
    for (const Contribution* c = first; c != first + count; ++c)
        if (c->radiance.is_finite() && std::isfinite(c->time))
            arrivals_[local].push_back(
                {recorded_time(c->time, sensor_distance, world_time_), pilot_energy(c->radiance)});
}

std::unique_ptr<FilmBlock> PilotBlock::deliver(TemporalFilter& filter) const {
    for (const KeptSample& k : kept_samples_)
        if (const size_t local = local_pixel(k.pos); local != SIZE_MAX)
            add_arrivals(local, &kept_[k.first], k.count, k.sensor_distance);
    for (int y = 0; y < h_; ++y)
        for (int x = 0; x < w_; ++x) {
            const size_t local = size_t(y) * size_t(w_) + size_t(x);
            auto& arrivals = arrivals_[local];
            if (arrivals.empty() && samples_[local] == 0) continue;
            filter.pilot_pixel(uint64_t(y0_ + y) * uint64_t(film_width_) + uint64_t(x0_ + x),
                               samples_[local], arrivals);
            std::vector<PilotArrival>().swap(arrivals);
        }
    if (!image_) return nullptr;
    ContributionList sample;
    for (const KeptSample& k : kept_samples_) {
        sample.clear();
        for (uint32_t i = k.first; i < k.first + k.count; ++i)
            sample.add(kept_[i].radiance, kept_[i].time, kept_[i].kernel);
        sample.set_sensor_distance(k.sensor_distance);
        sample.set_sample_index(k.sample_index);
        sample.set_is_splat(k.splat);
        image_->put(k.pos, sample);
    }
    return std::move(image_);
}

std::vector<ParamSpec> TimeResolvedFilm::inherited_params() {
    return inherit_params(
        inherit_params(Film::inherited_params(), "TimeResolvedFilm", time_grid_params()),
        "TimeResolvedFilm",
        {{"world_time", "boolean", "false",
          "bin by world time (the sensor segment removed, eq. 4.1) instead of camera time"},
         {"exposure", "float", "0", "exposure of the PNG preview(s), in stops"},
         {"prune_paths", "boolean", "true",
          "stop paths and skip connections once nothing they carry can arrive within the "
          "window (ch. 5.6.1); false: paths end only by max_depth or roulette (same image, "
          "slower: measures what pruning saves)"},
         {"tfilter", "tfilter", "histogram", "temporal reconstruction (nested)"}});
}

TimeResolvedFilm::TimeResolvedFilm(const Properties& props)
    : Film(props), grid_(read_time_grid(props)) {
    if (props.get_bool("world_time", false)) grid_.frame = TimeFrame::World;
    exposure_ = float(props.get_float("exposure", 0.0));
    prune_paths_ = props.get_bool("prune_paths", true);
    tfilter_ = std::static_pointer_cast<TemporalFilter>(
        props.child(PluginKind::TemporalFilter, "histogram"));
    tfilter_->prepare(grid_, width_, height_);
}

void TimeResolvedFilm::end_pilot() {
    tfilter_->end_pilot();
    pilot_ = false;
}

double TimeResolvedFilm::max_time() const {
    return world_time() ? std::numeric_limits<double>::infinity()
                        : grid_.end() + tfilter_->max_radius();
}

double TimeResolvedFilm::max_world_time() const {
    return world_time() ? grid_.end() + tfilter_->max_radius()
                        : std::numeric_limits<double>::infinity();
}

// Set while make_pilot_block() asks the subclass's make_block() for the tile's own block.
static thread_local bool making_image_block = false;

std::unique_ptr<FilmBlock> TimeResolvedFilm::make_pilot_block(int x0, int y0, int w, int h) const {
    if (!pilot_ || making_image_block) return nullptr;
    std::unique_ptr<FilmBlock> image;
    if (pilot_into_image_) {
        making_image_block = true;
        try {
            image = make_block(x0, y0, w, h);
        } catch (...) {
            making_image_block = false;
            throw;
        }
        making_image_block = false;
    }
    return std::make_unique<PilotBlock>(x0, y0, w, h, width_, world_time(), std::move(image));
}

void TimeResolvedFilm::warn_empty_window() const {
    const char* frame = world_time() ? "world" : "camera";
    if (arrivals_.count > 0 && arrivals_.inside == 0)
        log_warning(fmt::format(
            "no light arrived within the film's time window [{}, {}] ({} time, scene units): "
            "the light this render traced arrived between {:.6g} and {:.6g}; move the window "
            "(start, bin_width, bins) there",
            grid_.start, grid_.end(), frame, arrivals_.earliest, arrivals_.latest));
}

bool TimeResolvedFilm::merge_pilot(const FilmBlock& block) {
    const auto* pilot = pilot_ ? dynamic_cast<const PilotBlock*>(&block) : nullptr;
    if (!pilot) return false;  // (the image block of a pilot in the image merges as any block)
    if (std::unique_ptr<FilmBlock> image = pilot->deliver(*tfilter_)) merge(*image);
    return true;
}

void TimeResolvedFilm::add_expected_weight(double samples_per_pixel, std::vector<PixelSums>& sums,
                                           const std::vector<int>* rows) const {
    const std::vector<double> wx = filter_weight_integrals(true),
                              wy = filter_weight_integrals(false);
    const size_t W = size_t(width_), n_rows = rows ? rows->size() : size_t(height_);
    for (size_t r = 0; r < n_rows; ++r) {
        const double row = samples_per_pixel * wy[rows ? size_t((*rows)[r]) : r];
        for (size_t x = 0; x < W; ++x) sums[r * W + x].weight += row * wx[x];
    }
}

}  // namespace femto
