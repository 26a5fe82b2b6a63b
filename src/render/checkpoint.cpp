#include "render/checkpoint.h"

#include <unistd.h>
#include <zlib.h>

#include <cstdio>
#include <climits>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <memory>

#include "core/atomic_file.h"
#include "core/error.h"

namespace tessera {
namespace {

namespace fs = std::filesystem;

constexpr char kMagic[8] = {'T', 'E', 'S', 'S', 'C', 'K', 'P', 'T'};
constexpr uint32_t kFormatVersion = 2;
constexpr uint32_t kByteOrderMark = 0x01020304u;
/// magic + version + byte-order mark + header length + payload length + CRC.
constexpr uint64_t kFramingBytes = 8 + 4 + 4 + 8 + 8 + 4;

struct FileCloser {
    void operator()(FILE* f) const {
        if (f) std::fclose(f);
    }
};
using File = std::unique_ptr<FILE, FileCloser>;

/// The running CRC-32 continued over n bytes: zlib's crc32 takes an unsigned length, so huge films
/// are fed in chunks of 1 GiB.
uLong crc32Update(uLong crc, const void* p, size_t n) {
    const auto* b = static_cast<const Bytef*>(p);
    for (size_t done = 0; done < n;) {
        size_t k = std::min<size_t>(n - done, size_t(1) << 30);
        crc = crc32(crc, b + done, uInt(k));
        done += k;
    }
    return crc;
}

/// Appends bytes to a file and keeps the running CRC-32 of everything written.
class Writer {
public:
    Writer(FILE* f, const std::string& path) : f_(f), path_(path) {}
    void bytes(const void* p, size_t n) {
        if (n == 0) return;
        if (std::fwrite(p, 1, n, f_) != n) throw InputError(path_ + ": cannot write checkpoint: " + std::strerror(errno));
        crc_ = crc32Update(crc_, p, n);
    }
    template <class T>
    void value(const T& v) {
        bytes(&v, sizeof v);
    }
    template <class T>
    void array(const std::vector<T>& v) {
        bytes(v.data(), v.size() * sizeof(T));
    }
    uint32_t crc() const { return uint32_t(crc_); }

private:
    FILE* f_;
    const std::string& path_;
    uLong crc_ = crc32(0L, Z_NULL, 0);
};

/// Reads what Writer wrote, failing with "truncated" rather than reading past the end.
class Reader {
public:
    Reader(FILE* f, const std::string& path, uint64_t size) : f_(f), path_(path), left_(size) {}
    void bytes(void* p, size_t n, const char* what) {
        if (n > left_) throw InputError(path_ + ": checkpoint is truncated (ends inside the " + std::string(what) + ")");
        if (n > 0 && std::fread(p, 1, n, f_) != n)
            throw InputError(path_ + ": cannot read checkpoint (" + what + "): " + std::strerror(errno));
        left_ -= n;
        if (checksumming_) crc_ = crc32Update(crc_, p, n);
    }
    /// After readFraming has verified the checksum of the whole payload, reading it need not
    /// compute it again (a 4K film is 1.2 GB).
    void payloadVerified() { checksumming_ = false; }
    template <class T>
    T value(const char* what) {
        T v;
        bytes(&v, sizeof v, what);
        return v;
    }
    template <class T>
    void array(std::vector<T>& v, const char* what) {
        bytes(v.data(), v.size() * sizeof(T), what);
    }
    uint64_t left() const { return left_; }
    uint32_t crc() const { return uint32_t(crc_); }

private:
    FILE* f_;
    const std::string& path_;
    uint64_t left_;
    uLong crc_ = crc32(0L, Z_NULL, 0);
    bool checksumming_ = true;
};

std::string headerText(const CheckpointHeader& header) {
    std::string text;
    for (const auto& [key, value] : header) text += key + "=" + value + "\n";
    return text;
}

CheckpointHeader parseHeader(const std::string& text) {
    CheckpointHeader h;
    size_t pos = 0;
    while (pos < text.size()) {
        size_t eol = text.find('\n', pos);
        if (eol == std::string::npos) eol = text.size();
        std::string line = text.substr(pos, eol - pos);
        size_t eq = line.find('=');
        if (eq != std::string::npos) h.emplace_back(line.substr(0, eq), line.substr(eq + 1));
        pos = eol + 1;
    }
    return h;
}

/// Bytes of the payload for this film and state (what the writer writes, what the reader expects).
uint64_t payloadBytes(const Film& film, const RenderState& s) {
    uint64_t pixels = uint64_t(film.width()) * uint64_t(film.height());
    uint64_t n = 4 + 4 + 4 + 4 + 8 + 8 + 8 + 1 + 4 + 4 + 4 + 4 + 1;
    if (!s.tileDone.empty()) {
        n += s.tileDone.size();
        for (const auto& e : s.pendingSplats) n += 8 + e.size() * sizeof(SplatSink::Entry);
    }
    return n + pixels * (9 * sizeof(FilmAccum) + sizeof(uint32_t));
}

static_assert(sizeof(SplatSink::Entry) == 16, "checkpoint splat entries are 4-byte index + 3 floats");

}  // namespace

void writeCheckpoint(const std::string& path, const CheckpointHeader& header, const Film& film,
                     const RenderState& state) {
    writeFileAtomically(path, "checkpoint", [&](const std::string& tmp) {
        File f(std::fopen(tmp.c_str(), "wb"));
        if (!f) throw InputError(path + ": cannot write checkpoint: " + std::strerror(errno));
        Writer w(f.get(), path);
        w.bytes(kMagic, sizeof kMagic);
        w.value(kFormatVersion);
        w.value(kByteOrderMark);
        std::string text = headerText(header);
        w.value(uint64_t(text.size()));
        w.bytes(text.data(), text.size());
        w.value(payloadBytes(film, state));

        w.value(uint32_t(film.width()));
        w.value(uint32_t(film.height()));
        w.value(state.sppDone);
        w.value(state.passSpp);
        w.value(state.samples);
        w.value(state.nonFinite);
        w.value(state.seconds);
        w.value(uint8_t(state.firstNonFinite ? 1 : 0));
        SampleId first = state.firstNonFinite.value_or(SampleId{});
        w.value(int32_t(first.x));
        w.value(int32_t(first.y));
        w.value(first.sample);
        w.value(uint32_t(state.tileDone.size()));
        w.value(uint8_t(state.tileDone.empty() ? 0 : 1));
        if (!state.tileDone.empty()) {
            w.array(state.tileDone);
            for (const auto& entries : state.pendingSplats) {
                w.value(uint64_t(entries.size()));
                w.array(entries);
            }
        }
        w.array(film.sumData());
        w.array(film.sumSqData());
        w.array(film.splatData());
        w.array(film.countData());
        uint32_t crc = w.crc();
        if (std::fwrite(&crc, sizeof crc, 1, f.get()) != 1 || std::fflush(f.get()) != 0 || ::fsync(fileno(f.get())) != 0)
            throw InputError(path + ": cannot write checkpoint: " + std::strerror(errno));
        FILE* raw = f.release();
        if (std::fclose(raw) != 0) throw InputError(path + ": cannot finish writing checkpoint: " + std::strerror(errno));
    });
}

namespace {

/// Reads and checks the framing's start (magic number, version, byte order) and returns the header
/// text; checkpoints and partials share it.
std::string readHeaderText(Reader& r, const std::string& path) {
    char magic[8];
    r.bytes(magic, sizeof magic, "magic number");
    if (std::memcmp(magic, kMagic, sizeof magic) != 0) throw InputError(path + ": not a Tessera checkpoint or partial");
    uint32_t version = r.value<uint32_t>("format version");
    uint32_t bom = r.value<uint32_t>("byte-order mark");
    if (bom != kByteOrderMark) throw InputError(path + ": checkpoint was written on a machine of the other byte order");
    if (version != kFormatVersion)
        throw InputError(path + ": checkpoint format version " + std::to_string(version) + ", this tessera reads version " +
                         std::to_string(kFormatVersion));
    uint64_t headerBytes = r.value<uint64_t>("header length");
    if (headerBytes > r.left()) throw InputError(path + ": checkpoint is truncated (ends inside the header)");
    std::string text(headerBytes, '\0');
    r.bytes(text.data(), text.size(), "header");
    return text;
}

/// Reads and checks the framing up to the payload (magic number, version, byte order, lengths) and
/// verifies the CRC over the whole payload, leaving `f` at the payload's start. Returns the header text.
std::string readFraming(Reader& r, FILE* f, const std::string& path, uint64_t size) {
    std::string text = readHeaderText(r, path);

    // Verify the checksum over the whole file before trusting any length or value in it.
    uint64_t payload = r.value<uint64_t>("payload length");
    if (payload != r.left() - std::min<uint64_t>(r.left(), 4))
        throw InputError(path + ": checkpoint is truncated or has trailing bytes (" + std::to_string(size) + " bytes, expected " +
                         std::to_string(kFramingBytes + text.size() + payload) + ")");
    {
        long bodyStart = std::ftell(f);
        uLong crc = r.crc();
        std::vector<char> buf(1 << 20);
        uint64_t left = payload;
        while (left > 0) {
            size_t k = size_t(std::min<uint64_t>(left, buf.size()));
            if (std::fread(buf.data(), 1, k, f) != k) throw InputError(path + ": cannot read checkpoint payload");
            crc = crc32(crc, reinterpret_cast<const Bytef*>(buf.data()), uInt(k));
            left -= k;
        }
        uint32_t stored = 0;
        if (std::fread(&stored, sizeof stored, 1, f) != 1) throw InputError(path + ": checkpoint is truncated (no checksum)");
        if (uint32_t(crc) != stored) throw InputError(path + ": checkpoint is corrupt (CRC-32 mismatch)");
        std::fseek(f, bodyStart, SEEK_SET);
        r.payloadVerified();
    }
    return text;
}

/// The settings in the checkpoint's header must equal `expected`: the first that differs is named
/// with both values.
void checkSettings(const std::string& path, const std::string& text, const CheckpointHeader& expected) {
    CheckpointHeader found = parseHeader(text);
    for (const auto& setting : expected) {
        const std::string& key = setting.first;
        const std::string& value = setting.second;
        auto it = std::find_if(found.begin(), found.end(), [&](const auto& kv) { return kv.first == key; });
        std::string have = it == found.end() ? "(absent)" : it->second;
        if (have != value)
            throw InputError(path + ": checkpoint does not match this render: " + key + " is '" + have +
                             "' in the checkpoint, '" + value + "' now");
    }
}

/// The film size as writeCheckpoint stores it (the payload's first two values).
std::pair<uint32_t, uint32_t> readFilmSize(Reader& r) {
    uint32_t width = r.value<uint32_t>("resolution"), height = r.value<uint32_t>("resolution");
    return {width, height};
}

/// The scheduler's state (render/renderer.h) as writeCheckpoint stores it, after the film size.
RenderState readState(Reader& r, const std::string& path, uint32_t width, uint32_t height) {
    RenderState s;
    s.sppDone = r.value<uint32_t>("state");
    s.passSpp = r.value<uint32_t>("state");
    s.samples = r.value<uint64_t>("state");
    s.nonFinite = r.value<uint64_t>("state");
    s.seconds = r.value<double>("state");
    bool hasFirst = r.value<uint8_t>("state") != 0;
    SampleId first;
    first.x = r.value<int32_t>("state");
    first.y = r.value<int32_t>("state");
    first.sample = r.value<uint32_t>("state");
    if (hasFirst) s.firstNonFinite = first;
    uint32_t tiles = r.value<uint32_t>("state");
    bool partial = r.value<uint8_t>("state") != 0;
    if (s.passSpp == 0 || s.passSpp > 16) throw InputError(path + ": checkpoint is corrupt (pass of " + std::to_string(s.passSpp) + " spp)");
    const uint64_t pixels = uint64_t(width) * height;
    if (partial) {
        if (tiles > r.left()) throw InputError(path + ": checkpoint is truncated (ends inside the tile list)");
        s.tileDone.resize(tiles);
        r.array(s.tileDone, "tile list");
        s.pendingSplats.resize(tiles);
        for (auto& entries : s.pendingSplats) {
            uint64_t n = r.value<uint64_t>("splats");
            if (n > r.left() / sizeof(SplatSink::Entry)) throw InputError(path + ": checkpoint is truncated (ends inside the splats)");
            entries.resize(n);
            r.array(entries, "splats");
            for (const SplatSink::Entry& e : entries)
                if (e.pixelIndex >= pixels) throw InputError(path + ": checkpoint is corrupt (splat outside the image)");
        }
    }
    return s;
}

/// The film's accumulation state, the last part of the payload; nothing but the CRC may follow.
/// Bytes of film state per pixel: nine fixed-point sums (RGB sum, sum of squares, splat) and a count.
constexpr uint64_t kFilmBytesPerPixel = 9 * sizeof(FilmAccum) + sizeof(uint32_t);

void readFilm(Reader& r, const std::string& path, Film& film) {
    const uint64_t need = uint64_t(film.width()) * uint64_t(film.height()) * kFilmBytesPerPixel + 4;
    if (r.left() != need) throw InputError(path + ": checkpoint is corrupt (payload size does not match its contents)");
    r.array(film.sumData(), "film sums");
    r.array(film.sumSqData(), "film sums of squares");
    r.array(film.splatData(), "film splats");
    r.array(film.countData(), "film sample counts");
}

/// An open checkpoint or partial and its length; `missing` is the message when it cannot be sized.
struct OpenedFile {
    File file;
    uint64_t size = 0;
};

OpenedFile openForReading(const std::string& path, const std::string& missing) {
    std::error_code ec;
    OpenedFile o;
    o.size = fs::file_size(path, ec);
    if (ec) throw InputError(path + ": " + missing + " (" + ec.message() + ")");
    o.file.reset(std::fopen(path.c_str(), "rb"));
    if (!o.file) throw InputError(path + ": cannot open: " + std::strerror(errno));
    return o;
}

}  // namespace

RenderState readCheckpoint(const std::string& path, const CheckpointHeader& expected, Film& film) {
    auto [f, size] = openForReading(path, "no checkpoint to resume; render with --checkpoint SEC first");
    Reader r(f.get(), path, size);

    std::string text = readFraming(r, f.get(), path, size);
    checkSettings(path, text, expected);
    auto [width, height] = readFilmSize(r);
    if (int64_t(width) != film.width() || int64_t(height) != film.height())
        throw InputError(path + ": checkpoint film is " + std::to_string(width) + "x" + std::to_string(height) + ", this render " +
                         std::to_string(film.width()) + "x" + std::to_string(film.height()));
    RenderState s = readState(r, path, width, height);
    readFilm(r, path, film);
    return s;
}

CheckpointHeader readCheckpointHeader(const std::string& path) {
    auto [f, size] = openForReading(path, "cannot read");
    Reader r(f.get(), path, size);
    std::string text = readHeaderText(r, path);
    return parseHeader(text);
}

CheckpointContents readCheckpointContents(const std::string& path) {
    auto [f, size] = openForReading(path, "cannot read");
    Reader r(f.get(), path, size);

    CheckpointContents c;
    c.header = parseHeader(readFraming(r, f.get(), path, size));
    auto [width, height] = readFilmSize(r);
    // Allocate only what the file can hold: its length was checked against the payload length.
    if (width == 0 || height == 0 || width > uint32_t(INT32_MAX) || height > uint32_t(INT32_MAX) ||
        uint64_t(height) > r.left() / kFilmBytesPerPixel / width)
        throw InputError(path + ": checkpoint is corrupt (a " + std::to_string(width) + "x" + std::to_string(height) +
                         " film does not fit in its " + std::to_string(size) + " bytes)");
    c.state = readState(r, path, width, height);
    c.film = std::make_unique<Film>(int(width), int(height));
    readFilm(r, path, *c.film);
    return c;
}

}  // namespace tessera
