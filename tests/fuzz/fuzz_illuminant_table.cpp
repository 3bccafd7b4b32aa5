// libFuzzer target: the illuminant table (CSV of lamp kinds and chromaticities).

#include "fuzz_support.h"

#include <solo/lighting/illuminant_table.h>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return solo::fuzz::readInput(data, size, ".csv",
                               [](const std::filesystem::path& file) { (void)solo::readIlluminantTable(file); });
}
