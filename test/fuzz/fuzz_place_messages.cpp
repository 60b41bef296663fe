// libFuzzer target: see fuzz_entries.h. Built and run by `make fuzz` (test/fuzz/run_fuzz.sh).
#include "fuzz_entries.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
  openable_fuzz::placeMessages(data, size);
  return 0;
}
