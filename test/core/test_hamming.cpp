#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <sstream>
#include <string>
#include <type_traits>

#include "bit_oracle.h"
#include "openable/error.h"
#include "openable/hamming/hamming.h"

using namespace openable;
using openable_test::naiveBitCount;
using openable_test::randomWords;

namespace
{
/// Every kernel the library knows, whichever architecture it was built for.
const std::vector<HammingKernel> kAllKernels = {HammingKernel::kPortable, HammingKernel::kPopcnt, HammingKernel::kAvx2,
                                                HammingKernel::kAvx512Vpopcntdq, HammingKernel::kNeon};

bool isSupported(HammingKernel kernel)
{
  const auto kernels = supportedKernels();
  return std::find(kernels.begin(), kernels.end(), kernel) != kernels.end();
}
}  // namespace

TEST(Hamming, EveryKernelEqualsNaiveBitCountOnRandomDataOfManyLengths)
{
  std::mt19937_64 rng(7);
  const auto kernels = supportedKernels();
  ASSERT_GE(kernels.size(), 1u);
  for (size_t words = 0; words <= 70; ++words)
    for (int trial = 0; trial < 20; ++trial)
    {
      const auto a = randomWords(rng, words);
      auto b = randomWords(rng, words);
      if (trial == 0)
        b = a;  // distance 0
      if (trial == 1)
        for (size_t i = 0; i < words; ++i)
          b[i] = ~a[i];  // every bit differs
      const uint32_t expected = naiveBitCount(a.data(), b.data(), words);
      for (HammingKernel k : kernels)
        ASSERT_EQ(hamming(k, a.data(), b.data(), words), expected) << kernelName(k) << " words=" << words;
      ASSERT_EQ(hamming(a.data(), b.data(), words), expected);
    }
}

// Long descriptors with every bit different: the largest sums, past any accumulator a kernel flushes (NEON's
// 16-bit byte-count lanes every 4095 steps of two words).
TEST(Hamming, EveryKernelCountsLongDescriptorsWithEveryBitDifferent)
{
  std::mt19937_64 rng(13);
  for (size_t words : {8189u, 8190u, 8191u, 8192u, 20001u})
  {
    const auto a = randomWords(rng, words);
    std::vector<uint64_t> b(words);
    for (size_t i = 0; i < words; ++i)
      b[i] = ~a[i];
    for (HammingKernel k : supportedKernels())
      ASSERT_EQ(hamming(k, a.data(), b.data(), words), 64u * words) << kernelName(k) << " words=" << words;
  }
}

TEST(Hamming, RowKernelsEqualPairwiseDistancesWithStride)
{
  std::mt19937_64 rng(11);
  for (size_t words : {1u, 3u, 4u, 8u, 22u, 44u})
  {
    const size_t stride = words + 2;  // rows need not be packed
    const size_t count = 37;
    const auto query = randomWords(rng, words);
    const auto rows = randomWords(rng, stride * count);
    for (HammingKernel k : supportedKernels())
    {
      std::vector<uint32_t> out(count);
      hammingRow(k, query.data(), rows.data(), stride, words, count, out.data());
      for (size_t i = 0; i < count; ++i)
        ASSERT_EQ(out[i], naiveBitCount(query.data(), rows.data() + i * stride, words)) << kernelName(k);
    }
  }
}

// Packed rows (stride == words) of up to 8 words, as HOG-B's 6: the AVX-512 kernel handles eight rows at a
// time there, so every count around multiples of 8 is checked.
TEST(Hamming, RowKernelsEqualPairwiseDistancesOnPackedSmallRows)
{
  std::mt19937_64 rng(11);
  for (size_t words = 1; words <= 9; ++words)
    for (size_t count : {0u, 1u, 7u, 8u, 9u, 16u, 37u, 1000u})
    {
      const auto query = randomWords(rng, words);
      const auto rows = randomWords(rng, words * count + 1);  // one word past the last row: never read as a row
      for (HammingKernel k : supportedKernels())
      {
        std::vector<uint32_t> out(count + 1, 12345u);
        hammingRow(k, query.data(), rows.data(), words, words, count, out.data());
        for (size_t i = 0; i < count; ++i)
          ASSERT_EQ(out[i], naiveBitCount(query.data(), rows.data() + i * words, words))
              << kernelName(k) << " words=" << words << " count=" << count << " row " << i;
        EXPECT_EQ(out[count], 12345u) << kernelName(k) << ": wrote past the row";
      }
    }
}

// The nearest of a frame and its shifted views to each row: every kernel against the smallest naive bit count, on
// packed rows (the fused AVX-512 path for up to 4 queries and its fallback beyond) and strided ones, with
// counts around multiples of 8 and past a block of 256.
TEST(Hamming, RowNearestEqualsTheSmallestNaiveDistanceOfAnyQuery)
{
  std::mt19937_64 rng(23);
  for (size_t words : {1u, 2u, 3u, 6u, 8u, 9u, 22u})
    for (size_t stride : {words, words + 3})
      for (size_t nq : {1u, 2u, 3u, 4u, 5u})
        for (size_t count : {0u, 1u, 7u, 8u, 9u, 300u})
        {
          const auto query_words = randomWords(rng, nq * words);
          // Rows near the first query, so that every query is sometimes the nearest.
          auto rows = randomWords(rng, stride * count + 1);
          for (size_t i = 0; i < count; i += 3)
            std::copy(query_words.begin() + static_cast<long>((i % nq) * words),
                      query_words.begin() + static_cast<long>((i % nq + 1) * words),
                      rows.begin() + static_cast<long>(i * stride));
          std::vector<const uint64_t*> queries;
          for (size_t q = 0; q < nq; ++q)
            queries.push_back(query_words.data() + q * words);
          for (HammingKernel k : supportedKernels())
          {
            std::vector<uint32_t> out(count + 1, 12345u);
            hammingRowNearest(k, queries.data(), nq, rows.data(), stride, words, count, out.data());
            for (size_t i = 0; i < count; ++i)
            {
              uint32_t nearest = UINT32_MAX;
              for (size_t q = 0; q < nq; ++q)
                nearest = std::min(nearest, naiveBitCount(queries[q], rows.data() + i * stride, words));
              ASSERT_EQ(out[i], nearest) << kernelName(k) << " words=" << words << " stride=" << stride
                                         << " queries=" << nq << " count=" << count << " row " << i;
            }
            EXPECT_EQ(out[count], 12345u) << kernelName(k) << ": wrote past the row";
          }
        }
}

TEST(Hamming, RowNearestWithoutAQueryIsAClearError)
{
  const uint64_t row = 0;
  uint32_t out = 0;
  EXPECT_THROW(hammingRowNearest(nullptr, 0, &row, 1, 1, 1, &out), Error);
}

// The fused difference of two rows (the sequence recurrence's entering minus leaving term): packed rows of up
// to 9 words (the AVX-512 fused path and its fallback) and strided ones, every count around multiples of 8.
TEST(Hamming, RowDifferenceEqualsDifferenceOfNaiveDistances)
{
  std::mt19937_64 rng(17);
  for (size_t words : {1u, 2u, 5u, 6u, 8u, 9u, 22u})
    for (size_t stride : {words, words + 3})
      for (size_t count : {0u, 1u, 7u, 8u, 9u, 37u, 300u})
      {
        const auto qa = randomWords(rng, words);
        const auto qb = randomWords(rng, words);
        auto rows_a = randomWords(rng, stride * count + 1);
        auto rows_b = randomWords(rng, stride * count + 1);
        // The extremes, +64 and -64 in every word (the bias of the fused sum), and equal rows.
        for (size_t r = 0; r < count && (count == 8 || count == 9); ++r)
          for (size_t i = 0; i < words; ++i)
          {
            rows_a[r * stride + i] = count == 9 ? ~qa[i] : qa[i];
            rows_b[r * stride + i] = count == 9 ? qb[i] : ~qb[i];
          }
        if (count == 37)
          rows_b = rows_a;
        for (HammingKernel k : supportedKernels())
        {
          std::vector<int32_t> out(count + 1, 12345);
          hammingRowDifference(k, qa.data(), rows_a.data(), qb.data(), rows_b.data(), stride, words, count, out.data());
          for (size_t i = 0; i < count; ++i)
            ASSERT_EQ(out[i], int32_t(naiveBitCount(qa.data(), rows_a.data() + i * stride, words)) -
                                  int32_t(naiveBitCount(qb.data(), rows_b.data() + i * stride, words)))
                << kernelName(k) << " words=" << words << " stride=" << stride << " count=" << count << " row " << i;
          EXPECT_EQ(out[count], 12345) << kernelName(k) << ": wrote past the row";
        }
      }
}

// The in-place chain step (the steady state of the sequence sums) against a naive copy: each sum takes the
// old sum of the column before (the carry for the first) plus its row's distance to qa minus the term row i - L
// left for it (the caller's first L terms, then the step's own), and every row leaves its distance to qb L on.
TEST(Hamming, ChainStepEqualsNaiveShiftedSumsInPlace)
{
  std::mt19937_64 rng(23);
  for (size_t words : {1u, 5u, 6u, 8u, 9u, 22u})
    for (size_t stride : {words, words + 3})
      for (size_t count : {0u, 1u, 7u, 8u, 9u, 17u, 300u})
        for (size_t L : {1u, 3u, 8u, 20u})
        {
          const auto qa = randomWords(rng, words);
          const auto qb = randomWords(rng, words);
          const auto rows = randomWords(rng, stride * count + 1);
          std::vector<uint32_t> expected_leaving(count + L);
          for (size_t i = 0; i < L; ++i)
            expected_leaving[i] = uint32_t(rng() % (64 * words + 1));  // the caller's: any distance
          for (size_t i = 0; i < count; ++i)
            expected_leaving[i + L] = naiveBitCount(qb.data(), rows.data() + i * stride, words);
          // Old sums large enough that no new one goes negative, as in a full chain.
          std::vector<uint32_t> old_sums(count + 1);
          for (auto& s : old_sums)
            s = 64 * uint32_t(words) + uint32_t(rng() % 50000);
          const uint32_t carry = 64 * uint32_t(words) + 7;
          const auto naiveStep = [&](const auto& old)
          {
            auto expected = old;
            for (size_t i = 0; i < count; ++i)
              expected[i] = static_cast<typename std::decay_t<decltype(old)>::value_type>(
                  (i == 0 ? carry : old[i - 1]) + naiveBitCount(qa.data(), rows.data() + i * stride, words) -
                  expected_leaving[i]);
            return expected;
          };
          const auto smallestOf = [count](const auto& sums)
          { return count == 0 ? UINT32_MAX : uint32_t(*std::min_element(sums.begin(), sums.begin() + count)); };
          const std::vector<uint32_t> expected = naiveStep(old_sums);
          for (HammingKernel k : supportedKernels())
          {
            const std::string what = kernelName(k) + " words=" + std::to_string(words) +
                                     " stride=" + std::to_string(stride) + " count=" + std::to_string(count) +
                                     " L=" + std::to_string(L);
            std::vector<uint32_t> sums(old_sums);
            std::vector<uint32_t> leaving(expected_leaving.begin(), expected_leaving.begin() + L);
            leaving.resize(count + L, 12345);
            const uint32_t minimum = hammingChainStep(k, qa.data(), qb.data(), rows.data(), stride, words, count, L,
                                                      carry, sums.data(), leaving.data());
            ASSERT_EQ(sums, expected) << what << " (the last entry must stay untouched)";
            ASSERT_EQ(leaving, expected_leaving) << what;
            ASSERT_EQ(minimum, smallestOf(expected)) << what;
            // 16-bit sums and terms, where every sum fits.
            if (words > 8)
              continue;
            std::vector<uint16_t> narrow(old_sums.begin(), old_sums.end());
            const std::vector<uint16_t> narrow_expected = naiveStep(narrow);
            std::vector<uint16_t> narrow_leaving(expected_leaving.begin(), expected_leaving.begin() + L);
            narrow_leaving.resize(count + L, 12345);
            const uint32_t narrow_minimum = hammingChainStep(k, qa.data(), qb.data(), rows.data(), stride, words, count,
                                                             L, carry, narrow.data(), narrow_leaving.data());
            ASSERT_EQ(narrow, narrow_expected) << what << " 16-bit";
            ASSERT_EQ(std::vector<uint32_t>(narrow_leaving.begin(), narrow_leaving.end()), expected_leaving)
                << what << " 16-bit";
            ASSERT_EQ(narrow_minimum, smallestOf(narrow_expected)) << what << " 16-bit";
          }
        }
}

TEST(Hamming, BestKernelIsTheLastSupportedAndPortableAlwaysExists)
{
  const auto kernels = supportedKernels();
  EXPECT_EQ(kernels.front(), HammingKernel::kPortable);
  EXPECT_EQ(bestKernel(), kernels.back());
  for (HammingKernel k : kAllKernels)
    EXPECT_FALSE(kernelName(k).empty());
}

// No CPU runs both the x86 and the AArch64 kernels, so every host has one to refuse.
TEST(Hamming, UnsupportedKernelIsAClearError)
{
  size_t refused = 0;
  for (HammingKernel k : kAllKernels)
  {
    if (isSupported(k))
      continue;
    const uint64_t a = 1, b = 2;
    try
    {
      hamming(k, &a, &b, 1);
      ADD_FAILURE() << kernelName(k) << ": expected an error";
    }
    catch (const Error& e)
    {
      EXPECT_NE(std::string(e.what()).find("not supported"), std::string::npos) << e.what();
    }
    ++refused;
  }
  EXPECT_GE(refused, 1u);
}

// Names the kernels this host ran (in the output and as the test's property "kernels_exercised"), each forced
// through every entry point against the naive bit count. OPENABLE_EXPECT_HAMMING_KERNELS (names separated by
// spaces) makes a kernel that should have run and did not a failure: the aarch64 cross check sets "neon".
TEST(Hamming, KernelsExercisedAreNamedAndEachMatchesTheOracle)
{
  std::mt19937_64 rng(29);
  const size_t words = 6, count = 19, L = 3;
  const auto qa = randomWords(rng, words);
  const auto qb = randomWords(rng, words);
  const auto rows = randomWords(rng, words * count);
  std::vector<uint32_t> to_a(count), to_b(count);
  for (size_t i = 0; i < count; ++i)
  {
    to_a[i] = naiveBitCount(qa.data(), rows.data() + i * words, words);
    to_b[i] = naiveBitCount(qb.data(), rows.data() + i * words, words);
  }
  std::string exercised;
  for (HammingKernel k : supportedKernels())
  {
    const std::string name = kernelName(k);
    EXPECT_EQ(hamming(k, qa.data(), rows.data(), words), to_a[0]) << name;
    std::vector<uint32_t> row(count);
    hammingRow(k, qa.data(), rows.data(), words, words, count, row.data());
    EXPECT_EQ(row, to_a) << name;
    std::vector<int32_t> difference(count);
    hammingRowDifference(k, qa.data(), rows.data(), qb.data(), rows.data(), words, words, count, difference.data());
    for (size_t i = 0; i < count; ++i)
      EXPECT_EQ(difference[i], int32_t(to_a[i]) - int32_t(to_b[i])) << name << " row " << i;
    // A chain step, 32- and 16-bit, with every old sum and the carry 1000 and the caller's L leaving terms 0.
    const auto checkStep = [&](auto zero)
    {
      using Sum = decltype(zero);
      std::vector<Sum> sums(count, 1000), leaving(count + L, 0);
      hammingChainStep(k, qa.data(), qb.data(), rows.data(), words, words, count, L, 1000, sums.data(), leaving.data());
      for (size_t i = 0; i < count; ++i)
      {
        EXPECT_EQ(sums[i], 1000 + to_a[i] - (i < L ? 0 : to_b[i - L])) << name << " column " << i << " " << sizeof(Sum);
        EXPECT_EQ(leaving[i + L], to_b[i]) << name << " column " << i << " " << sizeof(Sum);
      }
    };
    checkStep(uint32_t(0));
    checkStep(uint16_t(0));
    exercised += (exercised.empty() ? "" : " ") + name;
  }
  std::cout << "Hamming kernels exercised: " << exercised << std::endl;
  RecordProperty("kernels_exercised", exercised);

  const char* expected = std::getenv("OPENABLE_EXPECT_HAMMING_KERNELS");
  std::istringstream names(expected ? expected : "");
  for (std::string name; names >> name;)
  {
    const bool ran = std::any_of(kAllKernels.begin(), kAllKernels.end(),
                                 [&](HammingKernel k) { return kernelName(k) == name && isSupported(k); });
    EXPECT_TRUE(ran) << "kernel " << name
                     << " was expected (OPENABLE_EXPECT_HAMMING_KERNELS) but did not run; ran: " << exercised;
  }
}

TEST(Hamming, L2DistanceKnownAnswer)
{
  const float a[] = {0, 0, 0};
  const float b[] = {1, 2, 2};
  EXPECT_FLOAT_EQ(l2Distance(a, b, 3), 3.0f);
  EXPECT_FLOAT_EQ(l2Distance(b, b, 3), 0.0f);
}
