// libFuzzer target: any byte string given to the JOBS-file parser of `tessera batch` must either
// parse or throw an InputError, never crash, hang or leak (run under ASan+UBSan by tools/fuzz.sh).
// The file is named inside a folder so that relative paths are resolved against it.
#include <cstdint>
#include <string_view>

#include "app/batch_jobs.h"
#include "core/error.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    std::string_view text(reinterpret_cast<const char*>(data), size);
    try {
        tessera::app::BatchFile file = tessera::app::parseBatchJobs(text, "fuzz/jobs.json");
        for (const tessera::app::BatchJob& job : file.jobs) (void)job.label();
    } catch (const tessera::InputError&) {
    }
    return 0;
}
