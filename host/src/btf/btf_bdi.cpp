// The BDI format (uncompressed bidirectional images) and the mapped-file cursor under every
// Bonn reader. A BDI stores, after its header, the ABRDFs (all light x view x channel values of
// one texel, as half floats, the channel fastest, then the light, then the view) of the texels
// in scan-line order (x fastest), in chunks of `scan lines per chunk` rows, each chunk prefixed
// by its size in bytes. A sparse BDI (compression 2) leaves out the texels its mask clears;
// they read as black.
#include <Imath/half.h>
#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <vector>

#include "btf/btf_format.h"
#include "femto/error.h"
#include "femto/input_file.h"

namespace femto::btf::detail {

MappedFile::MappedFile(const std::string& path) : path_(path) {
    const std::string problem = input_file_problem(path);
    if (!problem.empty()) throw SceneError("cannot open \"" + path + "\": " + problem);
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    struct stat st {};
    if (fd < 0 || ::fstat(fd, &st) != 0) {
        const std::string why = std::strerror(errno);
        if (fd >= 0) ::close(fd);
        throw SceneError("cannot open \"" + path + "\": " + why);
    }
    size_ = uint64_t(st.st_size);
    if (size_ > 0) {
        void* p = ::mmap(nullptr, size_, PROT_READ, MAP_PRIVATE, fd, 0);
        if (p == MAP_FAILED) {
            const std::string why = std::strerror(errno);
            ::close(fd);
            throw SceneError("cannot map \"" + path + "\" into memory: " + why);
        }
        data_ = static_cast<const uint8_t*>(p);
    }
    ::close(fd);  // the mapping stays valid
}

MappedFile::~MappedFile() {
    if (data_) ::munmap(const_cast<uint8_t*>(data_), size_);
}

void Reader::fail(const std::string& field, const std::string& what) const {
    throw SceneError("BTF \"" + path() + "\": " + field + ": " + what);
}

void Reader::expect(uint64_t count, uint64_t item_bytes, const char* field) const {
    // count * item_bytes may overflow for absurd counts: compare by division instead.
    if (item_bytes > 0 && count > remaining() / item_bytes)
        fail(field, "needs " + std::to_string(count) + " x " + std::to_string(item_bytes) +
                        " bytes but the file ends " + std::to_string(remaining()) +
                        " bytes later (truncated, or a corrupt size in the header)");
}

void Reader::expect_end() const {
    if (remaining() != 0)
        fail("end of file", std::to_string(remaining()) +
                                " bytes follow the last field: the header's sizes do not match "
                                "the file's length");
}

namespace {

class BdiData final : public Data {
public:
    BdiData(Header h, std::shared_ptr<const MappedFile> file, std::vector<int64_t> storage_index,
            std::vector<const uint16_t*> chunks, uint64_t texels_per_chunk)
        : Data(std::move(h)),
          file_(std::move(file)),
          storage_index_(std::move(storage_index)),
          chunks_(std::move(chunks)),
          texels_per_chunk_(texels_per_chunk),
          abrdf_size_(3 * header_.lights.size() * header_.views.size()) {}

    Color value(uint32_t x, uint32_t y, uint32_t l, uint32_t v) const override {
        const int64_t stored = storage_index_[x + uint64_t(header_.width) * y];
        if (stored < 0) return Color(0.f);  // left out of a sparse BDI
        const uint16_t* abrdf = chunks_[uint64_t(stored) / texels_per_chunk_] +
                                (uint64_t(stored) % texels_per_chunk_) * abrdf_size_;
        const uint16_t* bits = abrdf + 3 * (l + uint64_t(header_.lights.size()) * v);
        float raw[3];
        for (int c = 0; c < 3; ++c) {
            uint16_t b;
            std::memcpy(&b, bits + c, 2);  // the file's alignment is not guaranteed
            Imath::half h;
            h.setBits(b);
            raw[c] = float(h);
        }
        return finish(raw, l);
    }
    uint64_t memory_bytes() const override {
        return storage_index_.size() * sizeof(int64_t) + chunks_.size() * sizeof(void*);
    }

private:
    std::shared_ptr<const MappedFile> file_;
    std::vector<int64_t> storage_index_;  // texel -> stored ABRDF, -1 when left out
    std::vector<const uint16_t*> chunks_;
    uint64_t texels_per_chunk_;
    uint64_t abrdf_size_;
};

/// The mask (one byte per texel, x fastest) to the stored index of each texel.
std::vector<int64_t> storage_indices(Reader& in, const Header& h, bool sparse) {
    const uint64_t texels = uint64_t(h.width) * h.height;
    in.expect(texels, 1, "texel mask");
    std::vector<int64_t> index(texels);
    int64_t stored = 0;
    for (uint64_t i = 0; i < texels; ++i) {
        const bool present = in.u8("texel mask") != 0;
        index[i] = (present || !sparse) ? stored++ : -1;
    }
    return index;
}

std::vector<const uint16_t*> chunk_table(Reader& in, uint64_t stored, uint64_t per_chunk,
                                         uint64_t abrdf_bytes) {
    std::vector<const uint16_t*> chunks;
    for (uint64_t first = 0; first < stored; first += per_chunk) {
        const std::string field = "chunk " + std::to_string(chunks.size());
        const uint64_t expected = std::min(per_chunk, stored - first) * abrdf_bytes;
        const uint32_t size = in.u32(field.c_str());
        if (size != expected)
            in.fail(field, "holds " + std::to_string(size) + " bytes; the header implies " +
                               std::to_string(expected));
        chunks.push_back(reinterpret_cast<const uint16_t*>(in.file()->data() + in.position()));
        in.skip(size, field.c_str());
    }
    return chunks;
}

}  // namespace

std::shared_ptr<const Data> read_bdi(Reader& in, Header h, bool has_compression_byte) {
    const uint32_t scan_lines = in.u32("scan lines per chunk");
    if (scan_lines == 0 || scan_lines > h.height)
        in.fail("scan lines per chunk", std::to_string(scan_lines) +
                                            "; expected 1 to the height (" +
                                            std::to_string(h.height) + ")");
    const uint8_t compression = has_compression_byte ? in.u8("compression") : 1;
    if (compression == 1)
        in.fail("compression",
                "bzip2-compressed chunks, which femto does not read; "
                "decompress the BDI with the Bonn btflib");
    if (compression != 0 && compression != 2)
        in.fail("compression",
                std::to_string(compression) + "; expected 0 (full) or 2 (sparse), uncompressed");
    std::vector<int64_t> index = storage_indices(in, h, compression == 2);
    skip_rotations(in);
    const uint64_t stored =
        index.empty() ? 0 : uint64_t(*std::max_element(index.begin(), index.end()) + 1);
    const uint64_t abrdf_bytes = 2 * 3 * uint64_t(h.lights.size()) * h.views.size();
    const uint64_t per_chunk = uint64_t(h.width) * scan_lines;
    std::vector<const uint16_t*> chunks = chunk_table(in, stored, per_chunk, abrdf_bytes);
    in.expect_end();
    return std::make_shared<BdiData>(std::move(h), in.file(), std::move(index), std::move(chunks),
                                     per_chunk);
}

}  // namespace femto::btf::detail
