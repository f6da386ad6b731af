// The identified model as a plant (docs/identify.md, "The identified model as
// a plant"): the model file read back, its plant the same as the custom plant
// of its num/den/delay, and the Monte Carlo draws from its covariance.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "pidlab/analysis/monte_carlo.h"
#include "pidlab/evaluation/evaluation.h"
#include "pidlab/plant_sim/process_model.h"
#include "pidlab/tune/model_file.h"
#include "spec_build.h"  // internal to pidlab::tune: the steps tested one by one
#include "test_status.h"

using pidlab::analysis::DrawPlants;
using pidlab::analysis::kMaxModelRedraws;
using pidlab::analysis::MonteCarloOptions;
using pidlab::analysis::PerturbedText;
using pidlab::evaluation::Evaluate;
using pidlab::evaluation::EvaluateOptions;
using pidlab::evaluation::Evaluation;
using pidlab::evaluation::LoopKind;
using pidlab::evaluation::LoopOptions;
using pidlab::plant_sim::ProcessModelKind;
using pidlab::plant_sim::ProcessModelUncertainty;
using pidlab::tune::ReadModelFile;

namespace pidlab {
namespace {

// A P2DU model (Kp, Tw, Zeta, Td) with correlated parameters, far enough
// from the invalid region that no draw of 20000 is redrawn in practice.
ProcessModelUncertainty P2duModel() {
  ProcessModelUncertainty m;
  m.kind = ProcessModelKind::kP2DU;
  m.values = {2.0, 0.8, 0.5, 0.3};
  const std::vector<double> sd = {0.05, 0.02, 0.03, 0.01};
  const double rho[4][4] = {{1, 0.5, -0.3, 0.2}, {0.5, 1, 0.1, -0.4}, {-0.3, 0.1, 1, 0}, {0.2, -0.4, 0, 1}};
  for (int i = 0; i < 4; ++i)
    for (int k = 0; k < 4; ++k) m.covariance.push_back(rho[i][k] * sd[i] * sd[k]);
  return m;
}

Plant PlantOf(const ProcessModelUncertainty& m) {
  Plant p;
  p.name = "model";
  const plant_sim::ProcessModel model = plant_sim::ModelFromValues(m.kind, m.values);
  p.tf = model.ToTransferFunction();
  p.delay_s = model.delay_s();
  p.model = std::make_shared<const ProcessModelUncertainty>(m);
  return p;
}

// Kp, Tw, Zeta, Td of a P2DU draw, read back from its plant.
std::vector<double> P2duParameters(const Plant& p) {
  const double tw = std::sqrt(p.tf.den[0] / p.tf.den[2]);
  return {p.tf.num[0] / p.tf.den[2], tw, p.tf.den[1] / p.tf.den[2] / (2.0 * tw), p.delay_s};
}

TEST(ModelDraws, SampleMeanAndCovarianceMatchTheModelsWithinFourSigma) {
  const ProcessModelUncertainty m = P2duModel();
  MonteCarloOptions mc;
  mc.samples = 20000;
  mc.seed = 11;
  int redrawn = -1;
  const std::vector<Plant> draws = DrawPlants(PlantOf(m), nullptr, mc, &redrawn);
  ASSERT_EQ(draws.size(), 20000u);
  EXPECT_EQ(redrawn, 0);
  const std::size_t p = 4;
  const double n = static_cast<double>(draws.size());
  std::vector<double> mean(p, 0.0), cov(p * p, 0.0);
  std::vector<std::vector<double>> x;
  for (const Plant& d : draws) {
    ASSERT_FALSE(d.tf.den.empty());
    x.push_back(P2duParameters(d));
    for (std::size_t i = 0; i < p; ++i) mean[i] += x.back()[i] / n;
  }
  for (const auto& v : x)
    for (std::size_t i = 0; i < p; ++i)
      for (std::size_t k = 0; k < p; ++k) cov[i * p + k] += (v[i] - mean[i]) * (v[k] - mean[k]) / (n - 1.0);
  for (std::size_t i = 0; i < p; ++i) {
    SCOPED_TRACE(i);
    EXPECT_NEAR(mean[i], m.values[i], 4.0 * std::sqrt(m.covariance[i * p + i] / n));
    for (std::size_t k = 0; k < p; ++k) {
      // The sample covariance's standard deviation for a normal vector.
      const double c_ii = m.covariance[i * p + i], c_kk = m.covariance[k * p + k],
                   c_ik = m.covariance[i * p + k];
      EXPECT_NEAR(cov[i * p + k], c_ik, 4.0 * std::sqrt((c_ii * c_kk + c_ik * c_ik) / n)) << "k " << k;
    }
  }
}

TEST(ModelDraws, InvalidDrawsAreRedrawnAndCounted) {
  // Td 0.01 s with a standard error of 0.02 s: about a third of the draws
  // have Td < 0; Tp1 0.1 s with 0.1 s: a sixth have Tp1 <= 0.
  ProcessModelUncertainty m;
  m.kind = ProcessModelKind::kP1D;
  m.values = {1.0, 0.1, 0.01};
  m.covariance = {0.01, 0, 0, 0, 0.01, 0, 0, 0, 4e-4};
  MonteCarloOptions mc;
  mc.samples = 2000;
  int redrawn = 0;
  const std::vector<Plant> draws = DrawPlants(PlantOf(m), nullptr, mc, &redrawn);
  EXPECT_GT(redrawn, 600);
  EXPECT_LT(redrawn, 2000);
  for (const Plant& d : draws) {
    ASSERT_EQ(d.tf.den.size(), 2u);
    EXPECT_GT(d.tf.den[0], 0.0);
    EXPECT_GE(d.delay_s, 0.0);
  }
}

TEST(ModelDraws, ADrawThatIsNeverAModelIsInvalidAfterTheCap) {
  ProcessModelUncertainty m;
  m.kind = ProcessModelKind::kP1D;
  m.values = {1.0, -50.0, 0.0};  // Tp1 far below 0: every draw is refused
  m.covariance = {1e-4, 0, 0, 0, 1e-4, 0, 0, 0, 1e-4};
  MonteCarloOptions mc;
  mc.samples = 3;
  int redrawn = 0;
  Plant nominal = PlantOf(m);
  const std::vector<Plant> draws = DrawPlants(nominal, nullptr, mc, &redrawn);
  EXPECT_EQ(redrawn, 3 * kMaxModelRedraws);
  for (const Plant& d : draws) EXPECT_TRUE(d.tf.den.empty());
}

TEST(ModelDraws, TheSameSeedGivesTheSameDrawsAndAnotherSeedOthers) {
  const Plant nominal = PlantOf(P2duModel());
  MonteCarloOptions mc;
  mc.samples = 5;
  const std::vector<Plant> a = DrawPlants(nominal, nullptr, mc), b = DrawPlants(nominal, nullptr, mc);
  mc.seed = 2;
  const std::vector<Plant> c = DrawPlants(nominal, nullptr, mc);
  for (int i = 0; i < 5; ++i) {
    EXPECT_EQ(a[i].tf.den, b[i].tf.den);
    EXPECT_EQ(a[i].delay_s, b[i].delay_s);
    EXPECT_NE(a[i].tf.den, c[i].tf.den);
  }
  EXPECT_EQ(PerturbedText(nominal, nullptr), "identified model's parameter covariance");
}

TEST(ModelDraws, AModelWithoutACovarianceDrawsItsCoefficientsAndKeepsItsDelay) {
  ProcessModelUncertainty m = P2duModel();
  m.covariance.clear();
  m.covariance_message = "rank-deficient Jacobian";
  const Plant nominal = PlantOf(m);
  MonteCarloOptions mc;
  mc.samples = 4;
  mc.spread = 0.1;
  for (const Plant& d : DrawPlants(nominal, nullptr, mc)) {
    EXPECT_EQ(d.tf.den.front(), 1.0);
    EXPECT_EQ(d.delay_s, 0.3);
  }
  EXPECT_EQ(PerturbedText(nominal, nullptr),
            "transfer-function coefficients (the identified model's covariance is not ok: rank-deficient "
            "Jacobian)");
}

// ---- The model file.

class ModelFile : public ::testing::Test {
 protected:
  std::string Write(const std::string& text) {
    path_ = ::testing::TempDir() + "model_plant_test_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name() + ".json";
    std::ofstream(path_) << text;
    return path_;
  }
  void TearDown() override { std::remove(path_.c_str()); }
  std::string path_;
};

// A P1D file as `pidlab identify --out` writes it (keys it adds are ignored).
const char* kP1dFile = R"({
  "model": "p1d",
  "parameters": {"Kp": {"value": 1.8075302350748164, "standard_error": 0.0183},
                 "Tp1": {"value": 1.3237304550808608, "standard_error": 0.0229},
                 "Td": {"value": 0.2892185601113724, "standard_error": 0.00798}},
  "transfer_function": {"num": [1.8075302350748164], "den": [1.3237304550808608, 1.0],
                        "delay_s": 0.2892185601113724},
  "fit_percent": 87.3,
  "covariance": {"ok": true, "message": "",
                 "matrix": [[3.3463e-4, 3.0871e-4, -6.756e-5], [3.0871e-4, 5.2235e-4, -1.0925e-4],
                            [-6.756e-5, -1.0925e-4, 6.370e-5]]}
})";

TEST_F(ModelFile, ItsPlantEvaluatesBitIdenticallyToTheCustomPlantOfItsTransferFunction) {
  spec::PlantSpec model_spec, custom_spec;
  model_spec.plant = "model:" + Write(kP1dFile);
  custom_spec.num = {1.8075302350748164};
  custom_spec.den = {1.3237304550808608, 1.0};
  custom_spec.delay_s = 0.2892185601113724;
  Plant model, custom;
  std::string error;
  ASSERT_TRUE(tune::BuildPlant(model_spec, spec::NameStyle::kFlag, &model, &error)) << error;
  ASSERT_TRUE(tune::BuildPlant(custom_spec, spec::NameStyle::kFlag, &custom, &error)) << error;
  ASSERT_TRUE(model.model);
  EXPECT_EQ(model.model->values,
            (std::vector<double>{1.8075302350748164, 1.3237304550808608, 0.2892185601113724}));
  EXPECT_EQ(model.model->covariance.size(), 9u);
  LoopOptions loop;
  loop.loop = LoopKind::kSampled;
  Evaluation a, b;
  const PidGains g{1.0, 0.5, 0.0};
  ASSERT_TRUE(IsOk(Evaluate(model, g, loop, EvaluateOptions{}, &a)));
  ASSERT_TRUE(IsOk(Evaluate(custom, g, loop, EvaluateOptions{}, &b)));
  EXPECT_EQ(a.iae, b.iae);
  EXPECT_GT(a.iae, 0.0);
}

TEST_F(ModelFile, TheModelKeyIsTheSameAsPlantModelColonFile) {
  spec::PlantSpec s;
  s.model = Write(kP1dFile);
  s.Normalize();
  EXPECT_EQ(s.plant, "model:" + path_);
  EXPECT_EQ(s.model, "");
}

// Each bad file: false, one line naming the file and the reason.
TEST_F(ModelFile, ABadFileIsRefusedWithOneLineNamingTheFileAndTheReason) {
  const std::string good = kP1dFile;
  auto replaced = [&good](const std::string& from, const std::string& to) {
    std::string s = good;
    s.replace(s.find(from), from.size(), to);
    return s;
  };
  const std::pair<std::string, std::string> cases[] = {
      {"is not valid JSON", "{\"model\": "},
      {"has no key \"transfer_function\"", replaced("\"transfer_function\"", "\"tf\"")},
      {"\"parameters.Kp.value\" \"x\" is not a number", replaced("1.8075302350748164,", "\"x\",")},
      {"\"model\" \"p3d\" must be p1d|p2d|p2du|p1di", replaced("\"p1d\"", "\"p3d\"")},
      {"\"covariance.matrix\" must be 3 x 3 (Kp, Tp1, Td)",
       replaced("[-6.756e-5, -1.0925e-4, 6.370e-5]]", "[-6.756e-5]]")},
      {"is not a valid p1d model: Tp1 -1.3 s must be > 0", replaced("1.3237304550808608, \"", "-1.3, \"")},
      {"is not a valid plant", replaced("[1.3237304550808608, 1.0]", "[0.0, 1.0]")},
  };
  for (const auto& [reason, text] : cases) {
    SCOPED_TRACE(reason);
    spec::PlantSpec s;
    s.plant = "model:" + Write(text);
    Plant p;
    std::string error;
    EXPECT_FALSE(tune::BuildPlant(s, spec::NameStyle::kFlag, &p, &error));
    EXPECT_NE(error.find(path_), std::string::npos) << error;
    EXPECT_NE(error.find(reason), std::string::npos) << error;
    EXPECT_EQ(error.find('\n'), std::string::npos) << error;
  }
  spec::PlantSpec missing;
  missing.plant = "model:/nonexistent/model.json";
  Plant p;
  std::string error;
  EXPECT_FALSE(tune::BuildPlant(missing, spec::NameStyle::kFlag, &p, &error));
  EXPECT_EQ(error,
            "--plant 'model:/nonexistent/model.json': model file '/nonexistent/model.json' cannot be read: "
            "No such file or directory");
}

// A tf file (docs/identify.md, "A general transfer function"): 2 poles, 1 zero.
const char* kTfFile = R"({
  "model": "tf", "poles": 2, "zeros": 1,
  "parameters": {"b0": {"value": 1.0}, "b1": {"value": 0.5}, "a0": {"value": 0.8}, "a1": {"value": 1.2},
                 "Td": {"value": 0.25}},
  "transfer_function": {"num": [0.5, 1.0], "den": [1.0, 1.2, 0.8], "delay_s": 0.25},
  "covariance": {"ok": true, "message": "",
                 "matrix": [[1e-4, 0, 0, 0, 0], [0, 1e-4, 0, 0, 0], [0, 0, 1e-4, 0, 0], [0, 0, 0, 1e-4, 0],
                            [0, 0, 0, 0, 1e-6]]}
})";

TEST_F(ModelFile, ATfFileIsAPlantWhoseDrawsComeFromItsCoefficientsCovariance) {
  spec::PlantSpec s;
  s.plant = "model:" + Write(kTfFile);
  Plant p;
  std::string error;
  ASSERT_TRUE(tune::BuildPlant(s, spec::NameStyle::kFlag, &p, &error)) << error;
  ASSERT_TRUE(p.model);
  EXPECT_EQ(p.model->kind, ProcessModelKind::kTf);
  EXPECT_EQ(p.model->poles, 2);
  EXPECT_EQ(p.model->zeros, 1);
  EXPECT_EQ(p.model->values, (std::vector<double>{1.0, 0.5, 0.8, 1.2, 0.25}));
  EXPECT_EQ(p.tf.den, (std::vector<double>{1.0, 1.2, 0.8}));
  EXPECT_EQ(p.delay_s, 0.25);
  ASSERT_TRUE(p.model->HasCovariance());
  EXPECT_NE(PerturbedText(p, nullptr).find("covariance"), std::string::npos) << PerturbedText(p, nullptr);
  // 20000 draws: every coefficient and Td with the file's mean and standard
  // deviation (sigma 0.01 and 0.001, independent) within four sigma of the
  // estimates' own spread, every denominator stable.
  MonteCarloOptions mc;
  mc.samples = 20000;
  mc.seed = 5;
  int redrawn = 0;
  const std::vector<Plant> draws = DrawPlants(p, nullptr, mc, &redrawn);
  ASSERT_EQ(draws.size(), 20000u);
  const std::vector<double> sigma = {0.01, 0.01, 0.01, 0.01, 0.001};
  std::vector<double> sum(5, 0.0), sum2(5, 0.0);
  for (const Plant& d : draws) {
    ASSERT_EQ(d.tf.num.size(), 2u);
    ASSERT_EQ(d.tf.den.size(), 3u);
    EXPECT_TRUE(d.tf.den[1] > 0.0 && d.tf.den[2] > 0.0);
    const double x[5] = {d.tf.num[1], d.tf.num[0], d.tf.den[2], d.tf.den[1], d.delay_s};  // b0 b1 a0 a1 Td
    for (int k = 0; k < 5; ++k) sum[k] += x[k], sum2[k] += x[k] * x[k];
  }
  const double n = 20000.0;
  for (int k = 0; k < 5; ++k) {
    const double mean = sum[k] / n, sd = std::sqrt(sum2[k] / n - mean * mean);
    EXPECT_NEAR(mean, p.model->values[static_cast<std::size_t>(k)], 4.0 * sigma[k] / std::sqrt(n)) << k;
    EXPECT_NEAR(sd, sigma[k], 4.0 * sigma[k] / std::sqrt(2.0 * n)) << k;
  }
  EXPECT_EQ(redrawn, 0);  // 80 sigma from instability
}

TEST_F(ModelFile, ATfFileWithoutItsShapeOrWithAnUnstableDenominatorIsRefused) {
  const std::string good = kTfFile;
  auto replaced = [&good](const std::string& from, const std::string& to) {
    std::string s = good;
    s.replace(s.find(from), from.size(), to);
    return s;
  };
  const std::pair<std::string, std::string> cases[] = {
      {"has no key \"poles\"", replaced("\"poles\": 2, ", "")},
      {"\"zeros\" 2 must be an integer in 0..1", replaced("\"zeros\": 1", "\"zeros\": 2")},
      {"\"poles\" 7 must be an integer in 1..6", replaced("\"poles\": 2", "\"poles\": 7")},
      {"has no key \"parameters.a2\"", replaced("\"poles\": 2, \"zeros\": 1", "\"poles\": 3, \"zeros\": 0")},
      {"the denominator has a root with a real part >= 0", replaced("\"value\": 1.2", "\"value\": -1.2")},
  };
  for (const auto& [reason, text] : cases) {
    SCOPED_TRACE(reason);
    spec::PlantSpec s;
    s.plant = "model:" + Write(text);
    Plant p;
    std::string error;
    EXPECT_FALSE(tune::BuildPlant(s, spec::NameStyle::kFlag, &p, &error));
    EXPECT_NE(error.find(reason), std::string::npos) << error;
  }
}

TEST_F(ModelFile, ADelayOrASpreadNextToAModelWithACovarianceIsRefused) {
  spec::EvaluateSpec s;
  s.plant.plant = "model:" + Write(kP1dFile);
  s.plant.delay_s = 0.1;
  Plant p;
  std::string error;
  EXPECT_FALSE(tune::BuildPlant(s.plant, spec::NameStyle::kFlag, &p, &error));
  EXPECT_NE(error.find("has its own dead time"), std::string::npos) << error;
  s.plant.delay_s = 0.0;
  s.spread = 0.2;
  analysis::MonteCarloOptions mc;
  EXPECT_FALSE(tune::BuildMonteCarlo(s, spec::NameStyle::kFlag, &mc, &error));
  EXPECT_NE(error.find("--spread 0.2: --plant"), std::string::npos) << error;
  s.spread = 0.1;  // the default: an echoed spec runs again
  EXPECT_TRUE(tune::BuildMonteCarlo(s, spec::NameStyle::kFlag, &mc, &error)) << error;
}

}  // namespace
}  // namespace pidlab
