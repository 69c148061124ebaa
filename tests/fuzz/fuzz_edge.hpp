// What the fuzz target and its seed writer agree on: how the first byte of an
// input picks the message type and the context, and the two contexts (a
// process of the shipped base run, and an observer between runs).
#pragma once
#include <cstddef>
#include <cstdint>
#include <tuple>
#include <utility>

#include "afford/bounds.hpp"
#include "tests/samples.hpp"

namespace afford::fuzz {

using wire::MessageTypes;
constexpr std::size_t kTypes = std::tuple_size_v<MessageTypes>;

// The first byte of an input: bit 0 says whether the context has the run's
// config, the bits above pick the type (modulo the number of types). The
// rest of the input is the datagram.
constexpr std::size_t typeOf(std::uint8_t selector) { return (selector >> 1) % kTypes; }
constexpr bool withRun(std::uint8_t selector) { return (selector & 1) != 0; }
constexpr std::uint8_t selector(std::size_t type, bool with_run) {
  return static_cast<std::uint8_t>(type << 1 | (with_run ? 1 : 0));
}

// The run of the samples (tests/samples.hpp), and the shipped protocol.
inline BoundsContext context(bool with_run) {
  static const ProtocolConfig observer = test::shippedProtocol();
  const RunConfig& run = test::sampleConfig();
  return with_run ? BoundsContext{&run.protocol, &run} : BoundsContext{&observer, nullptr};
}

// A value that names a type.
template <class T>
struct Type {
  using type = T;
};

// f(Type<Msg>{}) for the type Msg at `index` of MessageTypes.
template <class F, std::size_t... I>
void forType(std::size_t index, F&& f, std::index_sequence<I...>) {
  ((index == I ? f(Type<std::tuple_element_t<I, MessageTypes>>{}) : void()), ...);
}
template <class F>
void forType(std::size_t index, F&& f) {
  forType(index, f, std::make_index_sequence<kTypes>{});
}

}  // namespace afford::fuzz
