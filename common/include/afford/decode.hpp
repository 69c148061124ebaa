// Decoding one received buffer as a typed message: the edge's steps that
// need no bus (afford/edge.hpp): bounds before LCM's decoder, the decode, the
// type's field checks, the digest. Used by the edge, by replay on recorded
// events, and by the fuzz target (tests/fuzz).
#pragma once
#include <cstddef>
#include <string>

#include "afford/bounds.hpp"
#include "afford/checks.hpp"
#include "afford/seal.hpp"
#include "afford/wire.hpp"

namespace afford {

// Decode one buffer as Msg: fingerprint, bounds, fields, digest (the edge's
// steps 1, 3, 4 and 5); false with the reason, naming the field.
template <class Msg>
bool decodeChecked(const void* data, std::size_t size, const BoundsContext& ctx, Msg& out, std::string& why) {
  if (!wire::checkWire<Msg>(data, size, boundsFor<Msg>(ctx), why)) return false;
  const int n = out.decode(data, 0, static_cast<int>(size));
  if (n < 0 || static_cast<std::size_t>(n) != size) {
    why = std::string("afford.") + wire::Bounds<Msg>::kName + " does not decode";
    return false;
  }
  if (std::string reason = checkMessage(out, ctx); !reason.empty()) {
    why = std::move(reason);
    return false;
  }
  if (!sealIntact(data, size)) {
    why = "field digest does not match the message (corrupted or forged)";
    return false;
  }
  return true;
}

}  // namespace afford
