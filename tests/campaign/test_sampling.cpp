// Designs: LHS stratification, Sobol' discrepancy, reproducibility, and the structure of the others.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "sampling/design.h"

using namespace flume::sampling;

namespace {

Distribution uniform(double lo, double hi) {
  Distribution d;
  d.type = DistributionType::kUniform;
  d.lower = lo;
  d.upper = hi;
  return d;
}

std::vector<Distribution> mixed_parameters() {
  std::vector<Distribution> ps;
  ps.push_back(uniform(0.15, 0.55));
  Distribution n;
  n.type = DistributionType::kNormal;
  n.mean = 1.0;
  n.std = 0.2;
  ps.push_back(n);
  ps.push_back(lognormal_from_mean_std(2.0, 0.5));
  Distribution t;
  t.type = DistributionType::kTruncatedNormal;
  t.mean = 0.0;
  t.std = 1.0;
  t.lower = -0.5;
  t.upper = 2.0;
  ps.push_back(t);
  Distribution b;
  b.type = DistributionType::kBeta;
  b.alpha = 2.0;
  b.beta = 5.0;
  b.lower = 1.0;
  b.upper = 3.0;
  ps.push_back(b);
  return ps;
}

DesignSpec spec(DesignType type, size_t samples, size_t levels = 0) {
  DesignSpec s;
  s.type = type;
  s.samples = samples;
  s.levels = levels;
  return s;
}

}  // namespace

// The defining property of LHS: with N points, each of the N equal-probability strata of every parameter
// holds exactly one point, measured through the parameter's own CDF.
TEST(Lhs, OnePointInEachStratumOfEveryDimension) {
  const auto params = mixed_parameters();
  for (size_t n : {1u, 2u, 7u, 64u, 257u}) {
    for (std::uint64_t seed : {1u, 7u, 12345u}) {
      const Design d = generate_design(params, {}, spec(DesignType::kLatinHypercube, n), seed);
      ASSERT_EQ(d.values.size(), n);
      for (size_t j = 0; j < params.size(); ++j) {
        std::vector<int> hits(n, 0);
        for (size_t i = 0; i < n; ++i) {
          const double p = cdf(params[j], d.values[i][j]);
          const auto stratum = static_cast<size_t>(std::min<double>(std::floor(p * n), n - 1));
          ++hits[stratum];
        }
        for (size_t k = 0; k < n; ++k)
          ASSERT_EQ(hits[k], 1) << "N=" << n << " seed=" << seed << " parameter " << j << " stratum " << k;
      }
    }
  }
}

TEST(Sobol, LowerCentredL2DiscrepancyThanMonteCarloAt256Points) {
  std::vector<Distribution> params(4, uniform(0.0, 1.0));
  for (std::uint64_t seed : {1u, 2u, 3u, 4u, 5u}) {
    const Design qmc = generate_design(params, {}, spec(DesignType::kSobol, 256), seed);
    const Design mc = generate_design(params, {}, spec(DesignType::kMonteCarlo, 256), seed);
    ASSERT_EQ(qmc.unit.size(), 256u);
    const double c2_qmc = centred_l2_discrepancy(qmc.unit), c2_mc = centred_l2_discrepancy(mc.unit);
    EXPECT_LT(c2_qmc, c2_mc) << "seed " << seed;
  }
}

// Two campaigns share points when one is a Monte Carlo design of the same seed with fewer samples: its points
// are the larger design's first ones, every parameter (not only the first), with a rank correlation too.
TEST(MonteCarlo, FewerSamplesOfTheSameSeedAreTheFirstPoints) {
  const auto params = mixed_parameters();
  for (const std::vector<RankCorrelation>& corr : {std::vector<RankCorrelation>{}, {{0, 2, 0.6}}}) {
    const Design big = generate_design(params, corr, spec(DesignType::kMonteCarlo, 120), 31);
    const Design small = generate_design(params, corr, spec(DesignType::kMonteCarlo, 12), 31);
    ASSERT_EQ(small.values.size(), 12u);
    for (size_t i = 0; i < small.values.size(); ++i) EXPECT_EQ(small.values[i], big.values[i]) << "point " << i;
  }
}

TEST(Designs, SameSeedSameDesignOtherSeedOtherDesign) {
  const auto params = mixed_parameters();
  for (DesignType t : {DesignType::kMonteCarlo, DesignType::kLatinHypercube, DesignType::kSobol, DesignType::kSaltelli}) {
    const Design a = generate_design(params, {}, spec(t, 32), 7);
    const Design b = generate_design(params, {}, spec(t, 32), 7);
    const Design c = generate_design(params, {}, spec(t, 32), 8);
    EXPECT_EQ(a.values, b.values) << to_string(t);
    EXPECT_NE(a.values, c.values) << to_string(t);
  }
}

// Saltelli's pick-freeze layout: A, B, then A with column i from B, as SaltelliSensitivityAlgorithm reads it.
TEST(Designs, SaltelliBlocksAreAWithOneColumnFromB) {
  const std::vector<Distribution> params(3, uniform(-M_PI, M_PI));
  const size_t n = 16;
  const Design d = generate_design(params, {}, spec(DesignType::kSaltelli, n), 3);
  ASSERT_EQ(d.values.size(), n * (3 + 2));
  EXPECT_EQ(d.saltelli_base_size, n);
  for (size_t i = 0; i < 3; ++i)
    for (size_t k = 0; k < n; ++k)
      for (size_t j = 0; j < 3; ++j)
        EXPECT_EQ(d.values[(2 + i) * n + k][j], j == i ? d.values[n + k][j] : d.values[k][j]);
}

TEST(Designs, GridCoversEveryLevelAndEveryChoice) {
  std::vector<Distribution> params = {uniform(0.0, 1.0)};
  Distribution c;
  c.type = DistributionType::kChoice;
  c.text_choices = {"sticky", "slip", "separate"};
  params.push_back(c);
  const Design d = generate_design(params, {}, spec(DesignType::kGrid, 0, 4), 1);
  ASSERT_EQ(d.values.size(), 12u);
  std::set<std::pair<double, double>> points;
  for (const auto& v : d.values) points.insert({v[0], v[1]});
  EXPECT_EQ(points.size(), 12u);
  std::set<double> levels, choices;
  for (const auto& v : d.values) {
    levels.insert(v[0]);
    choices.insert(v[1]);
  }
  EXPECT_EQ(levels, (std::set<double>{0.125, 0.375, 0.625, 0.875}));  // stratum midpoints of U(0, 1)
  EXPECT_EQ(choices, (std::set<double>{0, 1, 2}));
}

TEST(Designs, OneAtATimeMovesOneParameterFromTheMedians) {
  const std::vector<Distribution> params(3, uniform(0.0, 10.0));
  const Design d = generate_design(params, {}, spec(DesignType::kOneAtATime, 0, 2), 1);
  ASSERT_EQ(d.values.size(), 1u + 2 * 3 * 2);
  size_t centre = 0;
  for (const auto& v : d.values) {
    int moved = 0;
    for (double x : v) moved += std::abs(x - 5.0) > 1e-9;
    EXPECT_LE(moved, 1);
    centre += moved == 0;
  }
  EXPECT_EQ(centre, 1u);
}

// A rank correlation imposed through the normal copula: the sample's Spearman coefficient matches it within
// sampling error (standard error ~ (1 - rho^2) / sqrt(n) = 0.011 here; 0.05 is over 4 of them).
TEST(Designs, RankCorrelationIsImposed) {
  const auto params = mixed_parameters();
  const size_t n = 2000;
  const Design d = generate_design(params, {{0, 2, 0.7}}, spec(DesignType::kMonteCarlo, n), 11);
  auto ranks = [&](size_t j) {
    std::vector<size_t> idx(n);
    for (size_t i = 0; i < n; ++i) idx[i] = i;
    std::sort(idx.begin(), idx.end(), [&](size_t a, size_t b) { return d.values[a][j] < d.values[b][j]; });
    std::vector<double> r(n);
    for (size_t k = 0; k < n; ++k) r[idx[k]] = static_cast<double>(k);
    return r;
  };
  auto spearman = [&](size_t a, size_t b) {
    const auto ra = ranks(a), rb = ranks(b);
    const double mean = (n - 1) / 2.0;
    double sab = 0, saa = 0, sbb = 0;
    for (size_t i = 0; i < n; ++i) {
      sab += (ra[i] - mean) * (rb[i] - mean);
      saa += (ra[i] - mean) * (ra[i] - mean);
      sbb += (rb[i] - mean) * (rb[i] - mean);
    }
    return sab / std::sqrt(saa * sbb);
  };
  EXPECT_NEAR(spearman(0, 2), 0.7, 0.05);
  EXPECT_NEAR(spearman(0, 1), 0.0, 0.08);
}

TEST(Designs, ImpossibleCorrelationIsRejected) {
  const std::vector<Distribution> params(3, uniform(0.0, 1.0));
  // rho(0,1) = rho(0,2) = 0.9 but rho(1,2) = -0.9 is not a correlation matrix.
  EXPECT_THROW(generate_design(params, {{0, 1, 0.9}, {0, 2, 0.9}, {1, 2, -0.9}}, spec(DesignType::kMonteCarlo, 10), 1),
               std::invalid_argument);
}

TEST(Distributions, BoundsAreChecked) {
  EXPECT_EQ(check_distribution(uniform(0.0, 1.0)), "");
  EXPECT_NE(check_distribution(uniform(0.55, 0.15)).find("upper"), std::string::npos);
  Distribution c;
  c.type = DistributionType::kChoice;
  c.numeric_choices = {1.0};
  EXPECT_NE(check_distribution(c).find("values"), std::string::npos);
}
