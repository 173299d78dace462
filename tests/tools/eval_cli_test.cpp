// handtrack-eval on sequences it cannot score (issue 13): one clear line and a failing exit code,
// never a table of `nan`s with exit 0.
#include "handtrack/core/sequence.hpp"

#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace fs = std::filesystem;

namespace {

class EvalCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("handtrack-eval-test-" + std::to_string(::getpid()) + "-" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    // Four frames of empty depth (nothing in the working volume: no hand), each annotated.
    handtrack::CameraIntrinsics cam;
    handtrack::SequenceWriter writer(dir_ / "seq", cam);
    for (int f = 0; f < 4; ++f) {
      writer.write_depth(f, handtrack::DepthImage{cam, std::vector<float>(static_cast<size_t>(cam.width) * cam.height, 0.0F)});
      handtrack::Fingertips tips;
      tips[0] = Eigen::Vector3d(0, 0, 400);
      writer.write_fingertips(f, tips);
    }
    writer.flush();
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Runs handtrack-eval on the sequence; returns the exit code, stderr in *err.
  int eval(std::string* err) const {
    const fs::path out = dir_ / "stdout.txt", errf = dir_ / "stderr.txt";
    const std::string cmd = std::string("'") + HANDTRACK_EVAL_EXE + "' '" + (dir_ / "seq").string() + "' >'" +
                            out.string() + "' 2>'" + errf.string() + "' </dev/null";
    const int status = std::system(cmd.c_str());
    std::ifstream in(errf);
    std::stringstream text;
    text << in.rdbuf();
    *err = text.str();
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  }

  fs::path dir_;
};

TEST_F(EvalCli, NoScorableFrameIsAnErrorNotNan) {
  std::string err;
  EXPECT_NE(eval(&err), 0);
  EXPECT_NE(err.find("handtrack-eval: error: no frame could be scored"), std::string::npos) << err;
  EXPECT_EQ(err.find("nan"), std::string::npos) << err;
}

TEST_F(EvalCli, AnEmptyGroundTruthFileIsNotCalledMissing) {
  std::ofstream(dir_ / "seq" / "groundtruth.csv", std::ios::trunc).flush();
  std::string err;
  EXPECT_NE(eval(&err), 0);
  EXPECT_NE(err.find("groundtruth.csv: no annotated frame in it"), std::string::npos) << err;
  fs::remove(dir_ / "seq" / "groundtruth.csv");
  EXPECT_NE(eval(&err), 0);
  EXPECT_NE(err.find("no groundtruth.csv"), std::string::npos) << err;
}

}  // namespace
