#include "dreamsense/testing/analyzer_runner.hpp"

#include <gtest/gtest.h>

namespace dreamsense::testing {
namespace {

inline constexpr Key<int> kIn{"test.in"};
inline constexpr Key<int> kOut{"test.out"};
inline constexpr Key<int> kOther{"test.other"};

// Doubles test.in; optionally also writes a key it did not declare.
class Doubler : public Analyzer {
 public:
  explicit Doubler(bool cheat) : cheat_(cheat) {}
  std::string_view name() const override { return "doubler"; }
  AnalyzerContract contract() const override { return {{}, {}, {kIn.name}, {kOut.name}}; }
  Status process(const MultiFrame& in, const BlackboardView& prior,
                 BlackboardWriter& out) override {
    const auto v = prior.get(kIn);
    if (!v || v->stamp != in.stamp) return ok_status();
    if (!v->present()) {
      out.set_absent(kOut, in.stamp);
      return ok_status();
    }
    out.set(kOut, 2 * *v->value, in.stamp, v->confidence);
    if (cheat_) out.set(kOther, 1, in.stamp, 1.f);
    return ok_status();
  }

 private:
  bool cheat_;
};

TEST(AnalyzerRunner, PresetsFeedTheAnalyserAndItsWritesAreVisible) {
  AnalyzerRunner r(std::make_unique<Doubler>(false));
  const Timestamp t0 = Timestamp::from_ns(0), t1 = Timestamp::from_ns(40'000'000);
  r.preset(kIn, 21, t0, 0.5f);
  ASSERT_TRUE(r.run(t0, {}));
  ASSERT_TRUE(r.output(kOut));
  EXPECT_EQ(*r.output(kOut)->value, 42);
  EXPECT_FLOAT_EQ(r.output(kOut)->confidence, 0.5f);
  EXPECT_EQ(r.last_writes(), std::vector<std::string>{"test.out"});
  // Negative case: nothing preset in this tick, nothing written.
  ASSERT_TRUE(r.run(t1, {}));
  EXPECT_TRUE(r.last_writes().empty());
  r.preset_absent(kIn, Timestamp::from_ns(80'000'000));
  ASSERT_TRUE(r.run(Timestamp::from_ns(80'000'000), {}));
  EXPECT_FALSE(r.output(kOut)->present());
}

TEST(AnalyzerRunner, AWriteOutsideTheContractFails) {
  AnalyzerRunner r(std::make_unique<Doubler>(true));
  r.preset(kIn, 1, Timestamp::from_ns(0));
  auto s = r.run(Timestamp::from_ns(0), {});
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().message.find("test.other"), std::string::npos);
}

}  // namespace
}  // namespace dreamsense::testing
