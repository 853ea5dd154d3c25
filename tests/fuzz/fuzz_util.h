// libFuzzer entry points share this: the input as text, and a parser that may only refuse it with an
// InputError. Anything else escaping it (another exception, a crash, a leak, an unbounded allocation or a
// hang) is a finding.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>

#include "common/errors.h"

#ifndef FLUME_SOURCE_DIR
#define FLUME_SOURCE_DIR "."
#endif

namespace flume::fuzz {

template <class Parse>
int accept_or_input_error(const std::uint8_t* data, std::size_t size, Parse parse) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    parse(text);
  } catch (const InputError&) {
  }
  return 0;
}

}  // namespace flume::fuzz
