// The wire check before LCM's decode (afford/wire.hpp, afford/bounds.hpp and
// the generated afford/wire_bounds.hpp): every message type's own encoding
// passes; a cut, a trailing byte, a count or a string length out of bounds is
// refused, naming the field. And afford-lcmwire's project rules.
#include <gtest/gtest.h>
#include <zlib.h>

#include <algorithm>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>
#include <tuple>
#include <type_traits>
#include <vector>

#include "afford/bounds.hpp"
#include "afford/protocol.hpp"
#include "afford/decode.hpp"
#include "afford/seal.hpp"
#include "tests/samples.hpp"
#include "tests/support.hpp"

namespace afford {
namespace {

using wire::SizeField;
using Bytes = std::vector<std::uint8_t>;

static_assert(!std::is_default_constructible_v<wire::Max>, "a maximum is always given");

const RunConfig& runConfig() { return test::sampleConfig(); }
const ProtocolConfig& observerProtocol() {  // what a process uses between runs
  static const ProtocolConfig p = loadProtocol(std::string(AFFORD_SOURCE_DIR) + "/config");
  return p;
}
BoundsContext runContext() { return {&runConfig().protocol, &runConfig()}; }
BoundsContext observerContext() { return {&observerProtocol(), nullptr}; }

// ---- realistic messages of a run of the shipped base experiment (tests/samples.hpp) --

using test::focusImage;
using test::sample;
const std::string& kRunId = test::kSampleRunId;

template <class Msg>
Bytes encode(const Msg& m) {
  Bytes b(static_cast<std::size_t>(m.getEncodedSize()));
  EXPECT_EQ(m.encode(b.data(), 0, static_cast<int>(b.size())), static_cast<int>(b.size()));
  return b;
}

// Big-endian signed integers in an encoding.
std::int64_t get(const Bytes& b, std::size_t at, int width) {
  std::uint64_t u = 0;
  for (int i = 0; i < width; ++i) u = (u << 8) | b.at(at + static_cast<std::size_t>(i));
  if (width < 8 && (u >> (8 * width - 1)) != 0) u |= ~std::uint64_t{0} << (8 * width);
  return static_cast<std::int64_t>(u);
}
void put(Bytes& b, std::size_t at, int width, std::int64_t v) {
  auto u = static_cast<std::uint64_t>(v);
  for (int i = width - 1; i >= 0; --i, u >>= 8) b.at(at + static_cast<std::size_t>(i)) = u & 0xff;
}
bool fits(int width, std::int64_t v) {
  return width == 8 || (v >= -(std::int64_t{1} << (8 * width - 1)) && v < (std::int64_t{1} << (8 * width - 1)));
}

// Does the reason start by naming `field` ("field F = ..." or "field F: ...")?
bool names(const std::string& why, const std::string& field) {
  return why.rfind("field " + field + " = ", 0) == 0 || why.rfind("field " + field + ": ", 0) == 0;
}

// ---- every message type ----------------------------------------------------------------

template <class Msg>
class WireMessage : public ::testing::Test {
 protected:
  using Bounds = typename wire::Bounds<Msg>::type;

  WireMessage() : bounds_(boundsFor<Msg>(runContext())), bytes_(encode(sample(static_cast<const Msg*>(nullptr)))) {}

  bool passes(const Bytes& b, const Bounds& bounds) {
    return wire::checkWire<Msg>(b.data(), b.size(), bounds, why_);
  }
  bool passes(const Bytes& b) { return passes(b, bounds_); }
  // The size fields of the sample, found by the check itself.
  std::vector<SizeField> sizes(const Bounds& bounds) {
    std::vector<SizeField> found;
    std::string why;
    EXPECT_TRUE(wire::checkWire<Msg>(bytes_.data(), bytes_.size(), bounds, why, &found)) << why;
    return found;
  }
  std::vector<SizeField> sizes() { return sizes(bounds_); }
  // Bytes after a size field.
  std::size_t after(const SizeField& f) const { return bytes_.size() - f.offset - static_cast<std::size_t>(f.width); }

  Bounds bounds_;
  Bytes bytes_;
  std::string why_;
};

template <class>
struct TypesOf;
template <class... T>
struct TypesOf<std::tuple<T...>> {
  using type = ::testing::Types<T...>;
};
struct TypeNames {
  template <class T>
  static std::string GetName(int) {
    return wire::Bounds<T>::kName;
  }
};
TYPED_TEST_SUITE(WireMessage, TypesOf<wire::MessageTypes>::type, TypeNames);

TYPED_TEST(WireMessage, ItsEncodingPasses) {
  EXPECT_TRUE(this->passes(this->bytes_)) << this->why_;
  EXPECT_EQ(this->why_, "");
}

TYPED_TEST(WireMessage, APassingEncodingDecodesWhole) {
  ASSERT_TRUE(this->passes(this->bytes_)) << this->why_;
  TypeParam m;
  EXPECT_EQ(m.decode(this->bytes_.data(), 0, static_cast<int>(this->bytes_.size())),
            static_cast<int>(this->bytes_.size()));
  EXPECT_EQ(encode(m), this->bytes_);
}

TYPED_TEST(WireMessage, TheSampleFillsEveryArrayAndString) {
  const auto sizes = this->sizes();
  ASSERT_FALSE(sizes.empty());
  for (const SizeField& f : sizes)
    EXPECT_GT(get(this->bytes_, f.offset, f.width), f.is_string ? 1 : 0) << f.field << " is empty";
}

TYPED_TEST(WireMessage, EveryTruncationFails) {
  for (std::size_t n = 0; n < this->bytes_.size(); ++n) {
    const Bytes cut(this->bytes_.begin(), this->bytes_.begin() + static_cast<std::ptrdiff_t>(n));
    ASSERT_FALSE(this->passes(cut)) << "cut to " << n << " of " << this->bytes_.size() << " bytes";
    ASSERT_NE(this->why_.find(" needed, "), std::string::npos) << this->why_;
  }
}

TYPED_TEST(WireMessage, ATrailingByteFails) {
  Bytes longer = this->bytes_;
  longer.push_back(0);
  EXPECT_FALSE(this->passes(longer));
  EXPECT_EQ(this->why_, std::string("1 trailing byte after the last field of ") + wire::Bounds<TypeParam>::kName);
}

TYPED_TEST(WireMessage, AnotherFingerprintFails) {
  Bytes other = this->bytes_;
  other[7] ^= 1;
  EXPECT_FALSE(this->passes(other));
  EXPECT_EQ(this->why_.rfind("fingerprint ", 0), 0u) << this->why_;
}

TYPED_TEST(WireMessage, EachSizeAboveItsMaximumFailsNamingIt) {
  for (const SizeField& f : this->sizes()) {
    if (!fits(f.width, f.max + 1)) continue;  // the field cannot hold more than its maximum
    Bytes b = this->bytes_;
    put(b, f.offset, f.width, f.max + 1);
    EXPECT_FALSE(this->passes(b)) << f.field;
    EXPECT_TRUE(names(this->why_, f.field)) << f.field << ": " << this->why_;
  }
}

// Raised as far as the observer's larger maxima allow towards more elements
// than the bytes left hold. A count the run always sends at its maximum
// (n_actions of a prediction, n_trained) cannot be raised: it is covered by
// EachSizeAboveItsMaximumFailsNamingIt.
TYPED_TEST(WireMessage, EachCountBeyondTheBytesLeftFails) {
  const auto observer = boundsFor<TypeParam>(observerContext());
  for (const SizeField& f : this->sizes(observer)) {
    if (f.is_string) continue;  // EachStringLengthPastTheEndFails
    const std::int64_t now = get(this->bytes_, f.offset, f.width);
    const auto want = now + static_cast<std::int64_t>(this->after(f)) + 1;
    const std::int64_t raised = std::min(f.max, want);
    if (raised <= now || !fits(f.width, raised)) continue;
    Bytes b = this->bytes_;
    put(b, f.offset, f.width, raised);
    EXPECT_FALSE(this->passes(b, observer)) << f.field << " = " << raised;
    if (raised == want) {
      EXPECT_NE(this->why_.find(" needed, "), std::string::npos) << f.field << ": " << this->why_;
    }
  }
}

TYPED_TEST(WireMessage, EachSizeNegativeFailsNamingIt) {
  for (const SizeField& f : this->sizes()) {
    Bytes b = this->bytes_;
    put(b, f.offset, f.width, -1);
    EXPECT_FALSE(this->passes(b)) << f.field;
    EXPECT_TRUE(names(this->why_, f.field)) << f.field << ": " << this->why_;
  }
}

TYPED_TEST(WireMessage, EachStringLengthZeroFailsNamingIt) {
  for (const SizeField& f : this->sizes()) {
    if (!f.is_string) continue;
    Bytes b = this->bytes_;
    put(b, f.offset, f.width, 0);
    EXPECT_FALSE(this->passes(b)) << f.field;
    EXPECT_TRUE(names(this->why_, f.field)) << f.field << ": " << this->why_;
  }
}

TYPED_TEST(WireMessage, EachStringLengthHugeFailsNamingIt) {
  for (const SizeField& f : this->sizes()) {
    if (!f.is_string) continue;
    Bytes b = this->bytes_;
    put(b, f.offset, f.width, std::numeric_limits<std::int32_t>::max());
    EXPECT_FALSE(this->passes(b)) << f.field;
    EXPECT_TRUE(names(this->why_, f.field)) << f.field << ": " << this->why_;
  }
}

TYPED_TEST(WireMessage, EachStringLengthPastTheEndFails) {
  for (const SizeField& f : this->sizes()) {
    if (!f.is_string) continue;
    Bytes b = this->bytes_;
    const auto past = static_cast<std::int64_t>(this->after(f)) + 1;
    put(b, f.offset, f.width, past);
    EXPECT_FALSE(this->passes(b)) << f.field;
    EXPECT_EQ(this->why_, "field " + f.field + ": " + std::to_string(past) + " bytes needed, " +
                              std::to_string(past - 1) + " left");
  }
}

TYPED_TEST(WireMessage, EachStringWithoutItsNulFailsNamingIt) {
  for (const SizeField& f : this->sizes()) {
    if (!f.is_string) continue;
    Bytes b = this->bytes_;
    const auto length = static_cast<std::size_t>(get(b, f.offset, f.width));
    b.at(f.offset + 4 + length - 1) = 'x';
    EXPECT_FALSE(this->passes(b)) << f.field;
    EXPECT_EQ(this->why_, "field " + f.field + ": the string does not end with a NUL");
  }
}

// LCM's decode would keep the NUL inside the string and its encode stop at
// it: a handler would see a string that does not re-encode to its message.
TYPED_TEST(WireMessage, EachStringWithANulInsideFailsNamingIt) {
  for (const SizeField& f : this->sizes()) {
    if (!f.is_string) continue;
    Bytes b = this->bytes_;
    b.at(f.offset + 4) = 0;  // its first character
    EXPECT_FALSE(this->passes(b)) << f.field;
    EXPECT_EQ(this->why_, "field " + f.field + ": the string holds a NUL before its end");
  }
}

TYPED_TEST(WireMessage, ItsBoundsCannotBeLeftUnset) {
  // Every message type has a run_id, so its bounds hold a Max: `Bounds{}` does not compile.
  static_assert(!std::is_default_constructible_v<typename wire::Bounds<TypeParam>::type>);
  static_assert(wire::Bounds<TypeParam>::kMessage);
}

// ---- the hostile datagrams of docs/processes-and-channels.md ---------------------------
// None of these may reach LCM's decode: it would resize its vectors from the
// counts and read past the buffer. The tests never call it on them.

TEST(Wire, APredictionWithAHugeActionCountIsRefused) {
  prediction_t m = sample(static_cast<const prediction_t*>(nullptr));
  m.trained.clear();
  m.n_trained = 0;
  Bytes b = encode(m);
  const std::size_t at = 8 + (4 + kRunId.size() + 1) + 5 * 8;  // fingerprint, run_id, step, serial, prev_digest, x, y
  ASSERT_EQ(get(b, at, 4), kNumActions);
  put(b, at, 4, 0x10000001);  // sizeof(double) * count wraps in LCM's decode
  std::string why;
  EXPECT_FALSE(wire::checkWire<prediction_t>(b.data(), b.size(), boundsFor<prediction_t>(runContext()), why));
  EXPECT_EQ(why, "field n_actions = 268435457 exceeds its maximum 4");
  EXPECT_FALSE(wire::checkWire<prediction_t>(b.data(), b.size(), boundsFor<prediction_t>(observerContext()), why));
}

TEST(Wire, AStatusWithAHugeChannelCountIsRefused) {
  process_status_t m{};
  m.run_id = "";
  m.step = -1;
  m.process = "eye";
  m.pid = 1;
  m.state = process_status_t::WAITING;
  m.n_channels = 0;
  m.n_takes = 0;
  m.started = 0;
  m.n_copies = 0;
  m.digest = 0;
  Bytes b = encode(m);
  // n_channels, n_takes (0), host ("": its length and NUL), started, n_copies (0), then digest
  const std::size_t at = b.size() - 8 - 4 - 8 - 5 - 4 - 4;
  put(b, at, 4, 0x01000000);  // LCM's decode would allocate 16 M strings and counts
  std::string why;
  EXPECT_FALSE(
      wire::checkWire<process_status_t>(b.data(), b.size(), boundsFor<process_status_t>(observerContext()), why));
  EXPECT_EQ(why, "field n_channels = 16777216 exceeds its maximum " + std::to_string(kChannelCount));
}

TEST(Wire, AHugeOuterDimensionOverAnEmptyInnerOneIsRefused) {
  affordance_table_t m = sample(static_cast<const affordance_table_t*>(nullptr));
  m.affordance.clear();
  m.n_objects = 0;
  m.n_actions = 0;
  Bytes b = encode(m);
  const std::size_t at = b.size() - 8 - 4 - 4;  // n_objects, n_actions, no element, digest
  put(b, at, 4, std::numeric_limits<std::int32_t>::max());  // no bytes, but 2^31 empty rows in LCM's decode
  std::string why;
  EXPECT_FALSE(wire::checkWire<affordance_table_t>(b.data(), b.size(),
                                                   boundsFor<affordance_table_t>(observerContext()), why));
  EXPECT_EQ(why, "field n_objects = 2147483647 exceeds its maximum " +
                     std::to_string(observerProtocol().limits.objects));
}

TEST(Wire, AnErrorInsideANestedPartNamesItsPath) {
  prediction_t m = sample(static_cast<const prediction_t*>(nullptr));
  m.trained[0].run_id = std::string(300, 'r');
  const Bytes b = encode(m);
  std::string why;
  EXPECT_FALSE(wire::checkWire<prediction_t>(b.data(), b.size(), boundsFor<prediction_t>(runContext()), why));
  EXPECT_EQ(why, "field trained[0].run_id: 300 bytes exceed its maximum " +
                     std::to_string(runConfig().protocol.limits.name_bytes));
}

TEST(Wire, AnArrayOfStringsNamesTheElement) {
  process_status_t m = sample(static_cast<const process_status_t*>(nullptr));
  m.channels[1] = std::string(300, 'C');
  const Bytes b = encode(m);
  std::string why;
  EXPECT_FALSE(
      wire::checkWire<process_status_t>(b.data(), b.size(), boundsFor<process_status_t>(runContext()), why));
  EXPECT_EQ(why.rfind("field channels[1]: 300 bytes exceed", 0), 0u) << why;
}

TEST(Wire, TheMessageTypesAreTheChannelsTypes) {
  EXPECT_EQ(std::tuple_size_v<wire::MessageTypes>, kChannelCount);
  EXPECT_EQ(std::tuple_size_v<wire::SerialTypes>, channelNames(/*serial_only=*/true).size());
  static_assert(wire::Bounds<prediction_t>::kSerial && !wire::Bounds<process_status_t>::kSerial);
  static_assert(!wire::Bounds<trained_t>::kMessage && !wire::Bounds<sub_goal_t>::kMessage);
}

// ---- found by the fuzzer (tests/fuzz; the inputs are in tests/fuzz/regressions) -------

// nul-inside-string: LCM's decode kept the NUL inside a string, so a handler
// saw a string its own message does not encode (LCM's encode stops at a NUL).
TEST(Decode, AStringWithANulInsideIsRefused) {
  process_status_t m = sample(static_cast<const process_status_t*>(nullptr));
  Bytes b = sealed(m);
  std::vector<SizeField> sizes;
  std::string why;
  ASSERT_TRUE(wire::checkWire<process_status_t>(b.data(), b.size(), boundsFor<process_status_t>(observerContext()),
                                                why, &sizes));
  const auto f = std::find_if(sizes.begin(), sizes.end(), [](const SizeField& s) { return s.field == "counts_run"; });
  ASSERT_NE(f, sizes.end());
  b.at(f->offset + 4 + 16) = 0;  // "20240501-120000-\0ase-IMP-s1"
  sealBuffer(b.data(), b.size());
  process_status_t out{};
  EXPECT_FALSE(decodeChecked(b.data(), b.size(), observerContext(), out, why));
  EXPECT_EQ(why, "field counts_run: the string holds a NUL before its end");
}

// focus-side-overflow: an observer computed 3 * side * side before it checked
// the side, which overflows for most sides (undefined behaviour, UBSan).
TEST(Decode, AnObserverRefusesAFocusSideOfAnyIntNamingIt) {
  const int limit = observerProtocol().limits.focus_side;
  const auto refused = [&](auto m) {
    for (std::int32_t side : {std::numeric_limits<std::int32_t>::min(), -1824718621, -1, 0, limit + 1,
                              std::numeric_limits<std::int32_t>::max()}) {
      m.side = side;
      const Bytes b = sealed(m);
      decltype(m) out;
      std::string why;
      EXPECT_FALSE(decodeChecked(b.data(), b.size(), observerContext(), out, why)) << side;
      EXPECT_EQ(why, "field side = " + std::to_string(side) + " is out of range [1, " + std::to_string(limit) + "]");
    }
  };
  refused(sample(static_cast<const focus_t*>(nullptr)));
  refused(sample(static_cast<const effect_t*>(nullptr)));
}

// ---- the maxima of a context ----------------------------------------------------------

TEST(Bounds, FollowTheRunConfig) {
  const RunConfig& c = runConfig();
  const int side = c.eye.focus_side, px = c.world.size_px;
  EXPECT_EQ(boundsFor<focus_t>(runContext()).size.value, 3 * side * side);
  EXPECT_EQ(boundsFor<forward_prediction_t>(runContext()).size.value, 3 * side * side);
  EXPECT_EQ(boundsFor<object_probe_t>(runContext()).n_objects.value, static_cast<std::int64_t>(c.world.objects.size()));
  EXPECT_EQ(boundsFor<scene_t>(runContext()).size.value,
            static_cast<std::int64_t>(compressBound(static_cast<uLong>(3 * px * px))));
  EXPECT_EQ(boundsFor<extrinsic_result_t>(runContext()).n_sub_goals.value, c.planner.budget);
  EXPECT_EQ(boundsFor<prediction_t>(runContext()).n_actions.value, kNumActions);
  EXPECT_EQ(boundsFor<prediction_t>(runContext()).trained.run_id.value, c.protocol.limits.name_bytes);
  EXPECT_EQ(boundsFor<run_config_t>(runContext()).config_yaml.value, c.protocol.limits.config_bytes);
}

TEST(Bounds, WithoutARunConfigTheObserverLimitsApply) {
  const ProtocolLimits& l = observerProtocol().limits;
  EXPECT_EQ(boundsFor<focus_t>(observerContext()).size.value, 3 * l.focus_side * l.focus_side);
  EXPECT_EQ(boundsFor<effect_t>(observerContext()).size.value, 3 * l.focus_side * l.focus_side);
  EXPECT_EQ(boundsFor<object_probe_t>(observerContext()).n_objects.value, l.objects);
  EXPECT_EQ(boundsFor<affordance_table_t>(observerContext()).n_objects.value, l.objects);
  EXPECT_EQ(boundsFor<scene_t>(observerContext()).size.value,
            static_cast<std::int64_t>(compressBound(static_cast<uLong>(3 * l.scene_side * l.scene_side))));
  EXPECT_EQ(boundsFor<extrinsic_result_t>(observerContext()).n_sub_goals.value, l.sub_goals);
  EXPECT_EQ(boundsFor<process_status_t>(observerContext()).detail.value, l.text_bytes);
}

TEST(Bounds, AnObserverAcceptsAFocusImageLargerThanTheRunsOne) {
  focus_t m = sample(static_cast<const focus_t*>(nullptr));
  m.side = runConfig().eye.focus_side + 10;
  m.image = focusImage(m.side);
  m.size = static_cast<int32_t>(m.image.size());
  const Bytes b = encode(m);
  std::string why;
  EXPECT_TRUE(wire::checkWire<focus_t>(b.data(), b.size(), boundsFor<focus_t>(observerContext()), why)) << why;
  EXPECT_FALSE(wire::checkWire<focus_t>(b.data(), b.size(), boundsFor<focus_t>(runContext()), why));
  EXPECT_EQ(why, "field size = " + std::to_string(m.size) + " exceeds its maximum " +
                     std::to_string(3 * runConfig().eye.focus_side * runConfig().eye.focus_side));
}

// ---- afford-lcmwire ---------------------------------------------------------------------

class Lcmwire : public ::testing::Test {
 protected:
  Lcmwire() : dir_(test::tempDir("lcmwire")) {}
  ~Lcmwire() override { std::filesystem::remove_all(dir_); }
  // Runs the generator on one .lcm file of this text.
  test::CommandResult generate(const std::string& name, const std::string& text) {
    std::ofstream(dir_ + "/" + name) << text;
    return test::runCommand(std::string(AFFORD_LCMWIRE) + " --out " + out() + " " + dir_ + "/" + name);
  }
  std::string out() const { return dir_ + "/wire_bounds.hpp"; }
  std::string generated() const {
    std::ifstream in(out());
    return std::string(std::istreambuf_iterator<char>(in), {});
  }
  std::string dir_;
};

TEST_F(Lcmwire, RefusesAMessageWithoutTheTrailingDigest) {
  const auto r = generate("a_t.lcm",
                          "package t;\n"
                          "struct a_t {\n"
                          "  string run_id;\n"
                          "  int64_t step;\n"
                          "  int32_t x;\n"
                          "}\n");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("a_t.lcm:5: message type a_t must end with `int64_t digest;`"), std::string::npos)
      << r.output;
  EXPECT_FALSE(std::filesystem::exists(out()));
}

TEST_F(Lcmwire, RefusesADimensionThatIsNotAnEarlierIntegerField) {
  const std::string head = "package t;\nstruct a_t {\n  string run_id;\n  int64_t step;\n";
  const std::string tail = "  int64_t digest;\n}\n";
  for (const auto& [body, what] : std::vector<std::pair<std::string, std::string>>{
           {"  double x[n];\n  int32_t n;\n", "a_t.lcm:5: dimension 'n' of field 'x' names a later field"},
           {"  double x[m];\n", "a_t.lcm:5: dimension 'm' of field 'x' is neither an earlier field nor a constant"},
           {"  double n;\n  double x[n];\n",
            "a_t.lcm:6: dimension 'n' of field 'x' names 'double n', not a scalar integer"},
           {"  int8_t n;\n  double x[-1];\n", "a_t.lcm:6: dimension '-' of field 'x' must name an earlier integer"},
           {"  double x[999999999];\n",
            "a_t.lcm:5: constant dimension 999999999 of field 'x' is larger than 1048576, the most lcmwire accepts"},
           {"  double x[1048577];\n", "a_t.lcm:5: constant dimension 1048577 of field 'x' is larger than 1048576"},
           {"  double x[1024][1025];\n",
            "a_t.lcm:5: the constant dimensions of field 'x' hold 1049600 elements, more than 1048576"}}) {
    const auto r = generate("a_t.lcm", head + body + tail);
    EXPECT_NE(r.exit_code, 0) << body;
    EXPECT_NE(r.output.find(what), std::string::npos) << r.output;
  }
}

TEST_F(Lcmwire, RefusesASerialThatIsNotTheThirdField) {
  const auto r = generate("a_t.lcm",
                          "package t;\nstruct a_t {\n  string run_id;\n  int64_t step;\n  int8_t kind;\n"
                          "  int64_t serial;\n  int64_t digest;\n}\n");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("a_t.lcm:6: field 'serial' must be the third field"), std::string::npos) << r.output;
}

TEST_F(Lcmwire, ReadsConstantDimensionsConstsCommentsAndParts) {
  const auto r = generate("a_t.lcm",
                          "/* a block\n   comment */ package t;\n"
                          "struct p_t { string label; int16_t n; double v[n]; }\n"
                          "// the message\n"
                          "struct a_t {\n"
                          "  string run_id;  // the run\n"
                          "  int64_t step;\n"
                          "  double x[4];\n"
                          "  int8_t n;\n"
                          "  float grid[4][n];\n"
                          "  string names[n][2];\n"
                          "  p_t part;\n"
                          "  p_t parts[n];\n"
                          "  int64_t digest;\n"
                          "  const int8_t A = -1, B = 0x7f;\n"
                          "  const double HALF = 5e-1;\n"
                          "}\n");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string h = generated();
  for (const char* line : {"Max n;", "// elements of grid (dimension 2 of 2), names (dimension 1 of 2), parts\n",
                           "Max names;", "// bytes of each of names\n", "p_t_bounds part;", "p_t_bounds parts;",
                           "// each of parts\n",
                           "if (!c.primitive(\"x\", 8, 4)) return false;",
                           "if (!c.size(\"n\", 1, b.n, n_value)) return false;",
                           "if (!c.primitive(\"grid\", 4, product({4, n_value}))) return false;",
                           "if (!c.element(\"names\", {i0, i1}, [&] { return c.string(\"\", b.names); }))",
                           "if (!c.element(\"part\", {}, [&] { return Bounds<::t::p_t>::scan(c, b.part); }))",
                           "static constexpr bool kMessage = false;",  // p_t is a part
                           "using MessageTypes = std::tuple<::t::a_t>;", "using SerialTypes = std::tuple<>;"})
    EXPECT_NE(h.find(line), std::string::npos) << line << "\n" << h;
}

}  // namespace
}  // namespace afford
