// libFuzzer target: hostile bytes on every DICESIM_ channel into the aggregator and the worker.
// Build and run: tests/fuzz/README.md.
#include "tests/fuzz/message_handlers.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static dicesim::fuzz::Handlers handlers;  // state carries over between inputs, as on a live bus
  handlers.one(data, size);
  return 0;
}
