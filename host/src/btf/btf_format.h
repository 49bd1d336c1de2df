// Internal pieces of the Bonn BTF reader shared by its format parsers (femto/btf.h).
#pragma once

#include <cstdint>
#include <cstring>
#include <memory>
#include <string>

#include "femto/btf.h"

namespace femto::btf::detail {

constexpr uint32_t kMaxDirections = 4096;      // the Bonn files have 81 or 151
constexpr uint32_t kMaxTexels = 1u << 16;      // per side
constexpr uint32_t kMaxComponents = 1u << 16;  // per factorization

/// A whole file mapped read-only: measured BDIs are many gigabytes, so femto reads their
/// values in place instead of copying them.
class MappedFile {
public:
    /// Throws SceneError "cannot open "PATH": REASON".
    explicit MappedFile(const std::string& path);
    ~MappedFile();
    MappedFile(const MappedFile&) = delete;
    MappedFile& operator=(const MappedFile&) = delete;
    const uint8_t* data() const { return data_; }
    uint64_t size() const { return size_; }
    const std::string& path() const { return path_; }

private:
    std::string path_;
    const uint8_t* data_ = nullptr;
    uint64_t size_ = 0;
};

/// A cursor over a mapped file whose every read is bounded by the file's length; a failure is
/// a SceneError "BTF "PATH": FIELD: what is wrong".
class Reader {
public:
    explicit Reader(const std::string& path) : file_(std::make_shared<MappedFile>(path)) {}
    const std::string& path() const { return file_->path(); }
    std::shared_ptr<const MappedFile> file() const { return file_; }
    uint64_t position() const { return pos_; }
    uint64_t remaining() const { return file_->size() - pos_; }

    [[noreturn]] void fail(const std::string& field, const std::string& what) const;
    /// Fails unless `count` items of `item_bytes` each fit in the rest of the file.
    void expect(uint64_t count, uint64_t item_bytes, const char* field) const;
    /// Fails unless the file ends here.
    void expect_end() const;

    // (An empty file is mapped as null: memcpy must not see it, even for 0 bytes.)
    void bytes(void* out, uint64_t n, const char* field) {
        expect(n, 1, field);
        if (n > 0) std::memcpy(out, file_->data() + pos_, n);
        pos_ += n;
    }
    size_t peek(void* out, size_t n) const {
        n = size_t(std::min<uint64_t>(n, remaining()));
        if (n > 0) std::memcpy(out, file_->data() + pos_, n);
        return n;
    }
    void skip(uint64_t n, const char* field) {
        expect(n, 1, field);
        pos_ += n;
    }
    template <typename T>
    T scalar(const char* field) {
        T v;
        bytes(&v, sizeof(T), field);
        return v;
    }
    uint32_t u32(const char* field) { return scalar<uint32_t>(field); }
    int32_t i32(const char* field) { return scalar<int32_t>(field); }
    float f32(const char* field) { return scalar<float>(field); }
    uint8_t u8(const char* field) { return scalar<uint8_t>(field); }
    std::string text(uint64_t n, const char* field) {
        expect(n, 1, field);
        if (n == 0) return {};
        std::string s(reinterpret_cast<const char*>(file_->data() + pos_), size_t(n));
        pos_ += n;
        return s;
    }

private:
    std::shared_ptr<MappedFile> file_;
    uint64_t pos_ = 0;
};

/// Skips the list of per-texel frame rotations (femto ignores them, with a warning).
void skip_rotations(Reader& in);
/// The BDI-specific header after the extent, and the chunk table; the values stay mapped.
std::shared_ptr<const Data> read_bdi(Reader& in, Header h, bool has_compression_byte);

}  // namespace femto::btf::detail
