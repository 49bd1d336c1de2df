// Streak camera film (thesis ch. 4.3): x-t images of a few chosen rows. Each recorded row is
// reconstructed exactly as the `transient` film reconstructs that row of its x-y-t cube
// (<rfilter> in space, <tfilter> in time, histogram by default), so a streak image equals
// the corresponding slice of a transient cube rendered with the same scene and seed.
// Writes OUTBASE_rowRRRR.exr and OUTBASE_rowRRRR.png (its preview) for every recorded row.
// The EXR is the streak image format of viz::write_streak_exr (docs/viz.md): width x bins,
// x to the right, time increasing downward, float channels R, G, B and Z. Z is the pixel's
// depth as the transient film's depth part defines it (the mean sensor distance of the
// samples that hit something, weighted by the reconstruction filter; -1 where nothing was
// hit), repeated in every time row of the pixel's column; `femto viz unwarp` uses it.
//
// Memory: per recorded row, width * bins * 3 floats plus per-pixel filter weight and depth
// sums (double). The renderer skips rows whose samples cannot reach a recorded row
// (row_active).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <thread>

#include "femto/accumulator.h"
#include "femto/film.h"
#include "femto/image_io.h"
#include "femto/memory.h"
#include "femto/plugin.h"
#include "femto/tfilter.h"
#include "femto/time.h"
#include "femto/viz.h"

namespace {

using namespace femto;

class StreakFilm;

// One block: the recorded rows that fall inside a tile plus its filter border. The splat is
// TimeResolvedBlock's, as the transient film's; this block is its storage, which holds only
// the recorded rows (slot = index into rows_ * w_ + block column).
class StreakBlock final : public TimeResolvedBlock {
public:
    StreakBlock(const StreakFilm& film, int x0, int y0, int w, int h);
    void put(Vec2 pos, const ContributionList& sample) override { splat(pos, sample, *this); }

    // Storage of TimeResolvedBlock::splat().
    size_t slot(int x, int y) const {
        const int s = slot_of_y_[size_t(y - y0_)];
        return s < 0 ? SIZE_MAX : size_t(s) * size_t(w_) + size_t(x - x0_);
    }
    PixelSums& sums(size_t slot) { return sums_[slot]; }
    void add(size_t slot, int bin, float w, const Color& v) {
        double* dst = &data_[(slot * size_t(bins_) + size_t(bin)) * 3];
        dst[0] += w * v.r;
        dst[1] += w * v.g;
        dst[2] += w * v.b;
    }

    int bins_;
    std::vector<int> rows_;        // recorded rows inside [y0_, y0_ + h_)
    std::vector<int> slot_of_y_;   // per block row: index into rows_, or -1
    std::vector<double> data_;     // [rows_][w_][bins][3]; double as the transient film's blocks
    std::vector<PixelSums> sums_;  // [rows_][w_]
};

std::vector<int> parse_rows(const Properties& props, int height) {
    std::vector<int> rows;
    const bool has_rows = props.has("rows"), has_row = props.has("row");
    if (has_rows && has_row) props.fail("row", "give row or rows, not both");
    if (!has_rows && !has_row)
        props.fail("rows",
                   "the streak film needs the rows to record: row (integer) or rows "
                   "(comma-separated, e.g. \"64, 100\")");
    auto check = [&](const char* name, int64_t r) {
        if (r < 0 || r >= height)
            props.fail(name,
                       fmt::format("row {} is outside the image (rows 0 to {})", r, height - 1));
        if (std::find(rows.begin(), rows.end(), int(r)) != rows.end())
            props.fail(name, fmt::format("row {} is given twice", r));
        rows.push_back(int(r));
    };
    if (has_row) {
        check("row", props.get_int("row"));
        return rows;
    }
    const std::string text = props.get_string("rows");
    size_t pos = 0;
    while (true) {
        const size_t comma = text.find(',', pos);
        std::string item =
            text.substr(pos, comma == std::string::npos ? std::string::npos : comma - pos);
        const size_t a = item.find_first_not_of(" \t\n"), b = item.find_last_not_of(" \t\n");
        item = a == std::string::npos ? "" : item.substr(a, b - a + 1);
        if (item.empty() || item.find_first_not_of("0123456789") != std::string::npos ||
            item.size() > 9)
            props.fail("rows", fmt::format("rows must be comma-separated row indices (e.g. "
                                           "\"64, 100\"), got \"{}\"",
                                           text));
        check("rows", std::stoll(item));
        if (comma == std::string::npos) break;
        pos = comma + 1;
    }
    return rows;
}

class StreakFilm final : public TimeResolvedFilm {
public:
    explicit StreakFilm(const Properties& props) : TimeResolvedFilm(props) {
        rows_ = parse_rows(props, height_);
        std::sort(rows_.begin(), rows_.end());
        const double bytes = double(rows_.size()) * width_ * grid_.bins * 3 * sizeof(float);
        if (bytes > double(size_t(1) << 36))
            props.fail("bins", fmt::format("the streak images would need {:.1f} GiB (limit 64 GiB)",
                                           bytes / double(1 << 30)));
        if (const std::string problem =
                memory_shortfall(bytes + working_bytes(), "the streak images and their copies");
            !problem.empty())
            props.fail("bins", problem);
        slot_of_row_.assign(size_t(height_), -1);
        for (size_t i = 0; i < rows_.size(); ++i) slot_of_row_[size_t(rows_[i])] = int(i);
        // A sample in pixel row y lies in [y, y + 1); it reaches pixel row r when
        // |r + 0.5 - pos.y| <= radius (for_each_filter_pixel's footprint).
        const double radius = rfilter().radius();
        active_.assign(size_t(height_), 0);
        for (int y = 0; y < height_; ++y)
            for (int r : rows_)
                if (double(y) <= r + 0.5 + radius && double(y) + 1.0 > r + 0.5 - radius)
                    active_[size_t(y)] = 1;
        assign_in_huge_pages(data_, rows_.size() * size_t(width_) * size_t(grid_.bins) * 3, 0.f);
        sums_.assign(rows_.size() * size_t(width_), PixelSums());
    }

    // What a render holds besides the images, at most: a block per worker thread, each a tile's
    // recorded rows in double (the renderer's tiles are at most kMaxTileSize pixels across, plus
    // the filter's border), and while writing, one row's cube, its two slices and its depth.
    double working_bytes() const {
        const double tile = double(kMaxTileSize) + 2.0 * filter_border();
        const double row = double(width_) * grid_.bins * 3 * sizeof(float);
        const double block = std::min(double(rows_.size()), tile) * std::min(double(width_), tile) *
                             grid_.bins * 3 * sizeof(double);
        return 3.5 * row + double(std::max(1u, std::thread::hardware_concurrency())) * block;
    }

    std::unique_ptr<FilmBlock> make_block(int x0, int y0, int w, int h) const override {
        if (auto pilot = make_pilot_block(x0, y0, w, h)) return pilot;
        return std::make_unique<StreakBlock>(*this, x0, y0, w, h);
    }

    void start_pass(uint32_t pass) override { totals_.start(pass); }

    void merge(const FilmBlock& b) override {
        if (merge_pilot(b)) return;
        const auto& block = static_cast<const StreakBlock&>(b);
        merge_rejected(block);
        const size_t T3 = size_t(grid_.bins) * 3;
        for (size_t s = 0; s < block.rows_.size(); ++s) {
            const size_t slot = size_t(slot_of_row_[size_t(block.rows_[s])]);
            for (int bx = 0; bx < block.w(); ++bx) {
                const int x = block.x0() + bx;
                if (x < 0 || x >= width_) continue;
                const size_t src = s * size_t(block.w()) + size_t(bx);
                const size_t dst = slot * size_t(width_) + size_t(x);
                const PixelSums& in_sums = block.sums_[src];
                if (in_sums.empty()) continue;
                sums_[dst] += in_sums;
                const double* in = &block.data_[src * T3];
                float* out = &data_[dst * T3];
                for (size_t i = 0; i < T3; ++i) totals_.add(out[i], in[i], dst * T3 + i);
            }
        }
    }

    void add_splat_weight(double samples_per_pixel) override {
        add_expected_weight(samples_per_pixel, sums_, &rows_);
    }

    std::vector<Accumulator> accumulators() override {
        return with_window_accumulators({Accumulator::of(data_), Accumulator::of_doubles(sums_)});
    }

    bool row_active(int y) const override {
        return y >= 0 && y < height_ && active_[size_t(y)] != 0;
    }

    std::vector<float> steady_image() const override {
        std::vector<float> rgb(size_t(width_) * size_t(height_) * 3, 0.f);
        const size_t T = size_t(grid_.bins);
        for (size_t s = 0; s < rows_.size(); ++s)
            for (int x = 0; x < width_; ++x) {
                const size_t p = s * size_t(width_) + size_t(x);
                if (sums_[p].weight == 0) continue;
                double sum[3] = {0, 0, 0};
                for (size_t t = 0; t < T; ++t)
                    for (int c = 0; c < 3; ++c) sum[c] += data_[(p * T + t) * 3 + size_t(c)];
                float* o = &rgb[(size_t(rows_[s]) * size_t(width_) + size_t(x)) * 3];
                for (int c = 0; c < 3; ++c) o[c] = float(sum[c] / sums_[p].weight);
            }
        return rgb;
    }

    /// Recorded row `slot` as a cube of height 1 ([1][width][bins][3], normalised by the
    /// filter weights) with its depth, as the transient film computes both.
    io::Cube row_cube(size_t slot) const {
        const size_t T = size_t(grid_.bins), W = size_t(width_);
        io::Cube c;
        c.width = width_;
        c.height = 1;
        c.bins = grid_.bins;
        c.data.assign(W * T * 3, 0.f);
        c.depth.assign(W, -1.f);
        for (size_t x = 0; x < W; ++x) {
            const PixelSums& ps = sums_[slot * W + x];
            c.depth[x] = ps.depth();
            if (ps.weight == 0) continue;
            const float* in = &data_[(slot * W + x) * T * 3];
            float* out = &c.data[x * T * 3];
            for (size_t i = 0; i < T * 3; ++i) out[i] = float(in[i] / ps.weight);
        }
        return c;
    }

    std::vector<std::string> write(const std::string& out_base,
                                   const RenderInfo& info) const override {
        warn_empty_window();
        io::OutputSet files;
        for (size_t s = 0; s < rows_.size(); ++s) {
            io::Attributes attrs = io::time_resolved_attributes(grid_, info, tfilter_->type_name());
            attrs.push_back({"femto:row", std::to_string(rows_[s])});
            const io::Cube row = row_cube(s);
            const std::string base = fmt::format("{}_row{:04}", out_base, rows_[s]);
            // write_streak_exr adds femto:layout
            viz::write_streak_exr(files.add(base + ".exr"), row, 0, std::move(attrs));
            const std::vector<float> img = viz::streak_slice(row, 0);
            io::write_png_preview(files.add(base + ".png"), width_, grid_.bins, img.data(),
                                  exposure_);
        }
        return files.commit();
    }

    std::vector<int> rows_;         // sorted
    std::vector<int> slot_of_row_;  // per image row: index into rows_, or -1
    std::vector<char> active_;      // per image row: samples there reach a recorded row
    PassTotals totals_;             // how passes add into data_
    std::vector<float> data_;       // [rows_][width][bins][3]
    std::vector<PixelSums> sums_;   // [rows_][width]
};

StreakBlock::StreakBlock(const StreakFilm& film, int x0, int y0, int w, int h)
    : TimeResolvedBlock(film, x0, y0, w, h), bins_(film.grid().bins), slot_of_y_(size_t(h_), -1) {
    for (int r : film.rows_)
        if (r >= y0_ && r < y0_ + h_) {
            slot_of_y_[size_t(r - y0_)] = int(rows_.size());
            rows_.push_back(r);
        }
    data_.assign(rows_.size() * size_t(w_) * size_t(bins_) * 3, 0.f);
    sums_.assign(rows_.size() * size_t(w_), PixelSums());
}

}  // namespace

FEMTO_PLUGIN(StreakFilm, femto::PluginKind::Film, "streak",
             "Streak camera (ch. 4.3): x-t images of chosen rows, one EXR + PNG per row",
             {{"rows", "string", "", "rows to record, comma-separated (e.g. \"64, 100\")"},
              {"row", "integer", "", "the row to record (instead of rows)"}})
