#include "surrogate/ot_models.h"

#include <openturns/XMLStorageManager.hxx>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace flume::surrogate::detail {

OT::Sample to_sample(const std::vector<std::vector<double>>& rows) {
  const std::size_t d = rows.empty() ? 0 : rows[0].size();
  OT::Sample s(rows.size(), d);
  for (std::size_t i = 0; i < rows.size(); ++i)
    for (std::size_t j = 0; j < d; ++j) s(i, j) = rows[i][j];
  return s;
}

OT::Sample to_column(const std::vector<double>& values) {
  OT::Sample s(values.size(), 1);
  for (std::size_t i = 0; i < values.size(); ++i) s(i, 0) = values[i];
  return s;
}

std::vector<double> from_column(const OT::Sample& s) {
  std::vector<double> v(s.getSize());
  for (std::size_t i = 0; i < v.size(); ++i) v[i] = s(i, 0);
  return v;
}

int default_degree(std::size_t dimension, std::size_t n) {
  const OT::LinearEnumerateFunction e(dimension);
  int degree = 1;
  while (degree < 12 && e.getStrataCumulatedCardinal(degree + 1) <= n) ++degree;
  return degree;
}

OT::FunctionalChaosResult fit_chaos(const OT::Sample& x, const OT::Sample& y, const OT::Distribution& joint,
                                    int degree) {
  const std::size_t d = x.getDimension();
  OT::OrthogonalProductPolynomialFactory::PolynomialFamilyCollection families;
  for (std::size_t j = 0; j < d; ++j)
    families.add(OT::StandardDistributionPolynomialFactory(joint.getMarginal(j)));
  const OT::LinearEnumerateFunction enumerate(d);
  const OT::OrthogonalProductPolynomialFactory basis(families, enumerate);
  const OT::FixedStrategy adaptive(basis, enumerate.getStrataCumulatedCardinal(degree));
  // OpenTURNS ends the LARS path early once the error passes LeastSquaresMetaModelSelection-MaximumError
  // (0.5) and doubles its minimum; a noise-free polynomial output (exact after a few terms, its error then
  // jumping on round-off) stopped it after 2 of 4 terms. The whole path is walked instead and the model
  // with the least corrected leave-one-out error kept.
  OT::ResourceMap::SetAsScalar("LeastSquaresMetaModelSelection-MaximumError", 1e300);
  const OT::LeastSquaresStrategy projection{
      OT::LeastSquaresMetaModelSelectionFactory(OT::LARS(), OT::CorrectedLeaveOneOut())};
  OT::FunctionalChaosAlgorithm algo(x, y, joint, adaptive, projection);
  algo.run();
  return algo.getResult();
}

std::vector<OT::FunctionalChaosResult> chaos_replicates(const OT::FunctionalChaosResult& fitted, std::size_t count,
                                                        std::uint64_t seed) {
  const OT::Sample x = fitted.getInputSample(), y = fitted.getOutputSample();
  const std::size_t n = x.getSize();
  const OT::Function::FunctionCollection psi = fitted.getReducedBasis();
  const std::size_t k = psi.getSize();
  const OT::Sample z = fitted.getTransformation()(x);
  OT::Matrix design(n, k);
  for (std::size_t c = 0; c < k; ++c) {
    const OT::Sample col = psi[c](z);
    for (std::size_t i = 0; i < n; ++i) design(i, c) = col(i, 0);
  }
  OT::RandomGenerator::SetSeed(static_cast<OT::UnsignedInteger>(seed));
  std::vector<OT::FunctionalChaosResult> out;
  for (std::size_t b = 0; b < count; ++b) {
    const OT::Indices pick = OT::BootstrapExperiment::GenerateSelection(n, n);
    std::vector<OT::UnsignedInteger> distinct(pick.begin(), pick.end());
    std::sort(distinct.begin(), distinct.end());
    if (static_cast<std::size_t>(std::unique(distinct.begin(), distinct.end()) - distinct.begin()) <= k) continue;
    OT::Matrix a(n, k);
    OT::Point rhs(n);
    OT::Sample xb(n, x.getDimension()), yb(n, 1);
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t c = 0; c < k; ++c) a(i, c) = design(pick[i], c);
      rhs[i] = y(pick[i], 0);
      xb[i] = x[pick[i]];
      yb(i, 0) = rhs[i];
    }
    OT::Point coef;
    try {
      coef = a.solveLinearSystem(rhs);
    } catch (const OT::Exception&) {
      continue;
    }
    OT::Sample alpha(k, 1);
    for (std::size_t c = 0; c < k; ++c) alpha(c, 0) = coef[c];
    out.emplace_back(xb, yb, fitted.getDistribution(), fitted.getTransformation(), fitted.getInverseTransformation(),
                     OT::Function(), fitted.getOrthogonalBasis(), fitted.getIndices(), alpha, psi,
                     fitted.getResiduals(), fitted.getRelativeErrors());
  }
  return out;
}

namespace {
OT::KrigingResult fit_kriging_with(const OT::Sample& x, const OT::Sample& y, const OT::Basis& trend) {
  const std::size_t d = x.getDimension();
  OT::Point scale = x.computeStandardDeviation();
  for (auto& s : scale) s = s > 0 ? s : 1.0;
  const OT::MaternModel covariance(scale, OT::Point(1, std::max(y.computeStandardDeviation()[0], 1e-12)), 2.5);
  OT::KrigingAlgorithm algo(x, y, covariance, trend);
  // Scales searched up to 10 times the range of the runs (a flat direction is a long scale).
  OT::Point lower(d, 1e-2), upper(d);
  const OT::Point range = x.getMax() - x.getMin();
  for (std::size_t j = 0; j < d; ++j) {
    upper[j] = 10.0 * std::max(range[j], 1e-12);
    lower[j] = std::min(1e-2 * upper[j], lower[j]);
  }
  algo.setOptimizationBounds(OT::Interval(lower, upper));
  algo.run();
  return algo.getResult();
}
}  // namespace

OT::KrigingResult fit_kriging(const OT::Sample& x, const OT::Sample& y) {
  return fit_kriging_with(x, y, OT::ConstantBasisFactory(x.getDimension()).build());
}

OT::KrigingResult fit_kriging_quadratic_trend(const OT::Sample& x, const OT::Sample& y) {
  return fit_kriging_with(x, y, OT::QuadraticBasisFactory(x.getDimension()).build());
}

OT::KrigingResult fit_kriging_linear_trend(const OT::Sample& x, const OT::Sample& y) {
  return fit_kriging_with(x, y, OT::LinearBasisFactory(x.getDimension()).build());
}

OT::KrigingResult refit_kriging(const OT::KrigingResult& fitted, const OT::Sample& x, const OT::Sample& y) {
  OT::KrigingAlgorithm algo(x, y, fitted.getCovarianceModel(), fitted.getBasisCollection()[0]);
  algo.setOptimizeParameters(false);
  algo.run();
  return algo.getResult();
}

namespace {
// OpenTURNS' XML storage writes to a file: a private temporary one, removed after use.
struct TempFile {
  std::string path;
  TempFile() {
    std::string tmpl = (std::filesystem::temp_directory_path() / "flume_surrogate_XXXXXX").string();
    const int fd = mkstemp(tmpl.data());
    if (fd < 0) throw std::runtime_error("cannot create a temporary file in " + tmpl);
    close(fd);
    path = tmpl;
  }
  ~TempFile() { std::remove(path.c_str()); }
};
}  // namespace

std::string save_study(const OT::PersistentObject& object) {
  TempFile f;
  OT::Study study;
  study.setStorageManager(OT::XMLStorageManager(f.path));
  study.add("surrogate", object);
  study.save();
  std::ifstream in(f.path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

void load_study(const std::string& xml, OT::PersistentObject& object) {
  TempFile f;
  {
    std::ofstream out(f.path);
    out << xml;
  }
  OT::Study study;
  study.setStorageManager(OT::XMLStorageManager(f.path));
  study.load();
  study.fillObject("surrogate", object);
}

void quiet_warnings() { OT::Log::Show(OT::Log::ERROR); }

void rethrow(const OT::Exception& e) {
  std::string what = e.what();
  if (what.rfind("Error: ", 0) == 0) what = what.substr(7);
  std::replace(what.begin(), what.end(), '\n', ' ');
  throw std::runtime_error("OpenTURNS: " + what);
}

}  // namespace flume::surrogate::detail
