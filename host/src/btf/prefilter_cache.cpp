// The prefiltered hierarchy's disk cache (femto/btf_prefilter.h): building the hierarchy of a
// measured BTF takes PCA passes over gigabytes and dense angular filters, so it is kept next to
// the BTF, keyed by the file's size and CRC-32 (zlib) and every setting it depends on.
#include <zlib.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "btf/btf_format.h"
#include "femto/btf_prefilter.h"

namespace femto::btf {

namespace {

constexpr char kMagic[] = "femto-btf-hierarchy-1";

template <typename T>
void put(std::ostream& out, const T& v) {
    out.write(reinterpret_cast<const char*>(&v), sizeof(T));
}
template <typename T>
void put_vector(std::ostream& out, const std::vector<T>& v) {
    put<uint64_t>(out, v.size());
    out.write(reinterpret_cast<const char*>(v.data()), std::streamsize(v.size() * sizeof(T)));
}
template <typename T>
bool get(std::istream& in, T& v) {
    return bool(in.read(reinterpret_cast<char*>(&v), sizeof(T)));
}
/// Reads a vector whose size must fit in what is left of the file.
template <typename T>
bool get_vector(std::istream& in, uint64_t left, std::vector<T>& v) {
    uint64_t n = 0;
    if (!get(in, n) || n > left / sizeof(T)) return false;
    v.resize(size_t(n));
    return bool(in.read(reinterpret_cast<char*>(v.data()), std::streamsize(n * sizeof(T))));
}

uint32_t file_crc(const detail::MappedFile& file) {
    uLong crc = crc32(0L, Z_NULL, 0);
    constexpr uint64_t kChunk = 1u << 30;  // crc32() takes a uInt length
    for (uint64_t at = 0; at < file.size(); at += kChunk)
        crc = crc32(crc, file.data() + at, uInt(std::min(kChunk, file.size() - at)));
    return uint32_t(crc);
}

std::string cache_key(const std::string& path, const PrefilterSettings& s, const PcaSettings& p,
                      bool factorized) {
    const detail::MappedFile file(path);
    std::ostringstream key;
    key.precision(17);
    key << "size " << file.size() << " crc " << file_crc(file) << " kernel " << int(s.kernel)
        << " degree " << s.sh_degree << " regularization " << s.regularization << " cones";
    for (double a : s.cone_angles_deg) key << ' ' << a;
    if (factorized)
        key << " pca " << p.components << ' ' << p.oversampling << ' ' << p.power_iterations << ' '
            << p.seed;
    return key.str();
}

}  // namespace

void Hierarchy::save(const std::string& path, const std::string& key) const {
    const std::string temp = path + ".tmp";
    {
        std::ofstream out(temp, std::ios::binary);
        out.write(kMagic, sizeof(kMagic));
        put_vector(out, std::vector<char>(key.begin(), key.end()));
        put(out, lights_);
        put(out, views_);
        put(out, components_);
        put_vector(out, cones_);
        put_vector(out, widths_);
        put_vector(out, heights_);
        for (const auto* set : {&angular_, &spatial_}) {
            put<uint64_t>(out, set->size());
            for (const auto& v : *set) put_vector(out, v);
        }
        out.close();
        if (!out) {
            std::filesystem::remove(temp);
            throw std::runtime_error("cannot write \"" + temp + "\"");
        }
    }
    std::error_code ec;
    std::filesystem::rename(temp, path, ec);  // readers never see a half-written cache
    if (ec) {
        std::filesystem::remove(temp);
        throw std::runtime_error("cannot write \"" + path + "\": " + ec.message());
    }
}

std::shared_ptr<Hierarchy> Hierarchy::load(const std::string& path, const std::string& key) {
    std::error_code ec;
    const uint64_t size = std::filesystem::file_size(path, ec);
    if (ec) return nullptr;
    std::ifstream in(path, std::ios::binary);
    char magic[sizeof(kMagic)] = {};
    std::vector<char> stored;
    if (!in.read(magic, sizeof(magic)) || std::string(magic) != kMagic ||
        !get_vector(in, size, stored) || std::string(stored.begin(), stored.end()) != key)
        return nullptr;
    std::shared_ptr<Hierarchy> h(new Hierarchy());
    bool ok = get(in, h->lights_) && get(in, h->views_) && get(in, h->components_) &&
              get_vector(in, size, h->cones_) && get_vector(in, size, h->widths_) &&
              get_vector(in, size, h->heights_);
    for (auto* set : {&h->angular_, &h->spatial_}) {
        uint64_t n = 0;
        ok = ok && get(in, n) && n <= size;
        if (!ok) break;
        set->resize(size_t(n));
        for (auto& v : *set) ok = ok && get_vector(in, size, v);
    }
    // Consistent sizes, or the file is not used (a cache never makes a render fail).
    const size_t pairs = h->cones_.size() * h->cones_.size();
    ok = ok && h->widths_.size() == h->heights_.size() && h->angular_.size() == 3 * pairs &&
         h->spatial_.size() == 3 * h->widths_.size() && h->components_ <= kMaxComponents;
    for (size_t i = 0; ok && i < h->angular_.size(); ++i)
        ok = h->angular_[i].size() == uint64_t(h->lights_) * h->views_ * h->components_;
    for (size_t i = 0; ok && i < h->spatial_.size(); ++i)
        ok = h->spatial_[i].size() ==
             uint64_t(h->widths_[i / 3]) * h->heights_[i / 3] * h->components_;
    return ok ? h : nullptr;
}

std::shared_ptr<const Hierarchy> prefiltered(const std::string& path, const Data& data,
                                             const PrefilterSettings& settings,
                                             const PcaSettings& pca, bool use_cache,
                                             PrefilterReport& report) {
    const auto start = std::chrono::steady_clock::now();
    Factors factors;
    report.factorized = !linear_factors(data, factors);
    const std::string key = cache_key(path, settings, pca, report.factorized);
    std::ostringstream name;
    name << path << ".femto-prefilter-" << std::hex << std::hash<std::string>{}(key) << ".bin";
    std::shared_ptr<const Hierarchy> h;
    if (use_cache) {
        report.cache_file = name.str();
        h = Hierarchy::load(report.cache_file, key);
        report.from_cache = h != nullptr;
    }
    if (!h) {
        if (report.factorized) factors = factorize(data, pca, &report.pca);
        auto built = std::make_shared<Hierarchy>(factors, data.header().lights, data.header().views,
                                                 settings);
        if (use_cache) {
            try {
                built->save(report.cache_file, key);
            } catch (const std::exception& e) {
                report.cache_problem = e.what();
                report.cache_file.clear();
            }
        }
        h = built;
    }
    report.memory_bytes = h->memory_bytes();
    report.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return h;
}

}  // namespace femto::btf
