// libFuzzer target: any byte string read as a sample-range partial (render/partial.h, the
// checkpoint format of render/checkpoint.h) by the reader `tessera merge` uses must either merge or
// throw an InputError naming the problem, never crash, hang, leak or allocate more than the file
// can hold (run under ASan+UBSan by tools/fuzz.sh). The checksum check would stop most mutations
// at the door, so every input is also tried with its CRC-32 recomputed.
#include <unistd.h>
#include <zlib.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include "core/error.h"
#include "render/partial.h"

namespace {
std::string partialPath() {
    static const std::filesystem::path dir = [] {
        auto d = std::filesystem::temp_directory_path() / ("tessera-fuzz-partial-" + std::to_string(getpid()));
        std::filesystem::create_directories(d);
        return d;
    }();
    return (dir / "input.partial").string();
}

void tryMerge(const std::string& bytes) {
    const std::string path = partialPath();
    {
        std::ofstream out(path, std::ios::binary | std::ios::trunc);
        out.write(bytes.data(), std::streamsize(bytes.size()));
    }
    try {
        tessera::MergedRender m = tessera::mergePartials({path}, true);
        // Whatever merges must be usable.
        if (m.film.width() <= 0 || m.film.height() <= 0) __builtin_trap();
        (void)m.film.rgba();
    } catch (const tessera::InputError&) {
    }
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    std::string bytes(reinterpret_cast<const char*>(data), size);
    tryMerge(bytes);
    if (bytes.size() >= 4) {
        uLong crc = crc32(crc32(0L, Z_NULL, 0), reinterpret_cast<const Bytef*>(bytes.data()), uInt(bytes.size() - 4));
        uint32_t c = uint32_t(crc);
        std::memcpy(bytes.data() + bytes.size() - 4, &c, 4);
        tryMerge(bytes);
    }
    return 0;
}
