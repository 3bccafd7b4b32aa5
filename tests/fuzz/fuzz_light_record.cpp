// libFuzzer target: the light record (lights.json) that solo lights writes and solo night --lights reads.

#include "fuzz_support.h"

#include <solo/lighting/light_record.h>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return solo::fuzz::readInput(data, size, ".json",
                               [](const std::filesystem::path& file) { (void)solo::readLightRecord(file); });
}
