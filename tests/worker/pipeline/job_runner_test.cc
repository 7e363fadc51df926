#include "worker/pipeline/job_runner.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <fstream>
#include <limits>
#include <thread>

#include "tests/worker/pipeline/test_missions.h"
#include "worker/pipeline/stage.h"

namespace keel::pipeline {
namespace {

namespace fs = std::filesystem;

// A stage whose behaviour the test scripts.
class FakeStage : public Stage {
 public:
  using Body = std::function<StageResult(StageContext&)>;
  FakeStage(std::string name, Body body) : name_(std::move(name)), body_(std::move(body)) {}
  std::string name() const override { return name_; }
  StageResult run(StageContext& context) override { return body_(context); }

 private:
  std::string name_;
  Body body_;
};

class JobRunnerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("keel_job_runner_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    spec_.mission_dir = dir_ / "mission";
    spec_.work_dir = dir_ / "work";
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Stage `name` records that it ran, writes `<name>.txt` and reports {"n": <its index>}.
  void add_recording_stage(const std::string& name) {
    bodies_[name] = [this, name](StageContext& context) {
      order_.push_back(name);
      seen_reports_[name] = context.reports;
      seen_options_[name] = context.options;
      std::ofstream(context.work_dir / (name + ".txt")) << name;
      StageResult result;
      result.report = {{"n", static_cast<int>(order_.size())}};
      result.artifacts = {name + ".txt"};
      return result;
    };
  }

  JobRunner runner() {
    return JobRunner([this](const std::string& name) -> std::unique_ptr<Stage> {
      auto it = bodies_.find(name);
      if (it == bodies_.end()) throw std::invalid_argument("unknown stage '" + name + "'");
      return std::make_unique<FakeStage>(name, it->second);
    });
  }

  fs::path dir_;
  JobSpec spec_;
  std::map<std::string, FakeStage::Body> bodies_;
  std::vector<std::string> order_;
  std::map<std::string, nlohmann::json> seen_reports_;
  std::map<std::string, nlohmann::json> seen_options_;
};

TEST_F(JobRunnerTest, RunsStagesInOrderPassingEarlierReportsAndOptions) {
  for (const char* name : {"a", "b", "c"}) add_recording_stage(name);
  spec_.stages = {"b", "a", "c"};
  spec_.options = {{"a", {{"x", 3}}}};
  std::vector<std::string> started, done;
  JobHooks hooks;
  hooks.on_stage_start = [&](const std::string& s) { started.push_back(s); };
  hooks.on_stage_done = [&](const std::string& s, const StageResult& r, double) {
    done.push_back(s);
    EXPECT_TRUE(fs::exists(spec_.work_dir / r.artifacts.at(0)));
  };

  const JobResult result = runner().run(spec_, hooks);

  EXPECT_EQ(result.outcome, JobOutcome::kSucceeded) << result.error;
  EXPECT_EQ(order_, (std::vector<std::string>{"b", "a", "c"}));
  EXPECT_EQ(started, order_);
  EXPECT_EQ(done, order_);
  EXPECT_EQ(result.ran, order_);
  // Each stage sees exactly the sections of the stages before it.
  EXPECT_TRUE(seen_reports_["b"].empty());
  EXPECT_EQ(seen_reports_["a"], (nlohmann::json{{"b", {{"n", 1}}}}));
  EXPECT_EQ(seen_reports_["c"], (nlohmann::json{{"b", {{"n", 1}}}, {"a", {{"n", 2}}}}));
  EXPECT_EQ(seen_options_["a"], (nlohmann::json{{"x", 3}}));
  EXPECT_TRUE(seen_options_["b"].empty());
  EXPECT_EQ(result.reports["c"]["n"], 3);
}

TEST_F(JobRunnerTest, SkipsCompletedStagesAndKeepsTheirReports) {
  for (const char* name : {"a", "b", "c"}) add_recording_stage(name);
  spec_.stages = {"a", "b", "c"};
  spec_.completed = {{"a", {{"from", "earlier"}}, 4.5}, {"b", {{"from", "earlier too"}}, 1.25}};
  std::vector<std::string> done;
  JobHooks hooks;
  hooks.on_stage_done = [&](const std::string& s, const StageResult&, double) {
    done.push_back(s);
  };

  const JobResult result = runner().run(spec_, hooks);

  EXPECT_EQ(result.outcome, JobOutcome::kSucceeded);
  EXPECT_EQ(order_, std::vector<std::string>{"c"});
  EXPECT_EQ(done, std::vector<std::string>{"c"});
  EXPECT_EQ(result.ran, std::vector<std::string>{"c"});
  EXPECT_EQ(seen_reports_["c"]["a"]["from"], "earlier");
  EXPECT_EQ(seen_reports_["c"]["b"]["from"], "earlier too");
  EXPECT_DOUBLE_EQ(result.stage_seconds.at("a"), 4.5);
  EXPECT_DOUBLE_EQ(result.stage_seconds.at("b"), 1.25);
  EXPECT_EQ(result.reports.size(), 3u);
}

TEST_F(JobRunnerTest, CompletedStageUnknownToThisWorkerIsStillSkipped) {
  add_recording_stage("b");
  spec_.stages = {"a", "b"};
  spec_.completed = {{"a", nlohmann::json::object(), 1.0}};
  EXPECT_EQ(runner().run(spec_).outcome, JobOutcome::kSucceeded);
  EXPECT_EQ(order_, std::vector<std::string>{"b"});
}

TEST_F(JobRunnerTest, RecordsEachStageDuration) {
  const auto pause = std::chrono::milliseconds(60);
  bodies_["slow"] = [&](StageContext&) {
    std::this_thread::sleep_for(pause);
    return StageResult{};
  };
  add_recording_stage("quick");
  spec_.stages = {"slow", "quick"};
  std::map<std::string, double> hooked;
  JobHooks hooks;
  hooks.on_stage_done = [&](const std::string& s, const StageResult&, double seconds) {
    hooked[s] = seconds;
  };

  const JobResult result = runner().run(spec_, hooks);

  ASSERT_EQ(result.outcome, JobOutcome::kSucceeded);
  // The clock is steady: a stage that slept 60 ms cannot have taken less.
  EXPECT_GE(result.stage_seconds.at("slow"), 0.060);
  EXPECT_GE(result.stage_seconds.at("quick"), 0.0);
  EXPECT_EQ(hooked, result.stage_seconds);
}

TEST_F(JobRunnerTest, StageExceptionBecomesFailurePrefixedWithStageName) {
  add_recording_stage("a");
  bodies_["ingest"] = [](StageContext&) -> StageResult {
    throw std::runtime_error("mission.yaml: sensors[2].file: imu.csv not found");
  };
  add_recording_stage("c");
  spec_.stages = {"a", "ingest", "c"};
  std::vector<std::string> done;
  JobHooks hooks;
  hooks.on_stage_done = [&](const std::string& s, const StageResult&, double) {
    done.push_back(s);
  };

  const JobResult result = runner().run(spec_, hooks);

  EXPECT_EQ(result.outcome, JobOutcome::kFailed);
  EXPECT_EQ(result.error, "ingest: mission.yaml: sensors[2].file: imu.csv not found");
  EXPECT_EQ(result.failed_stage, "ingest");
  EXPECT_EQ(order_, std::vector<std::string>{"a"});  // c never ran
  EXPECT_EQ(done, std::vector<std::string>{"a"});
}

TEST_F(JobRunnerTest, UnknownStageFailsBeforeAnyStageRuns) {
  add_recording_stage("a");
  spec_.stages = {"a", "nope"};
  const JobResult result = runner().run(spec_);
  EXPECT_EQ(result.outcome, JobOutcome::kFailed);
  EXPECT_EQ(result.error, "nope: unknown stage 'nope'");
  EXPECT_TRUE(order_.empty());
}

TEST_F(JobRunnerTest, ArtifactThatWasNotWrittenFailsTheStage) {
  bodies_["a"] = [](StageContext&) {
    StageResult r;
    r.artifacts = {"missing.drc"};
    return r;
  };
  spec_.stages = {"a"};
  const JobResult result = runner().run(spec_);
  EXPECT_EQ(result.outcome, JobOutcome::kFailed);
  EXPECT_NE(result.error.find("a: artifact 'missing.drc' was not written"), std::string::npos)
      << result.error;
}

TEST_F(JobRunnerTest, ArtifactNameWithFolderFailsTheStage) {
  bodies_["a"] = [](StageContext& context) {
    fs::create_directories(context.work_dir / "sub");
    std::ofstream(context.work_dir / "sub" / "x") << "x";
    StageResult r;
    r.artifacts = {"sub/x"};
    return r;
  };
  spec_.stages = {"a"};
  const JobResult result = runner().run(spec_);
  EXPECT_EQ(result.outcome, JobOutcome::kFailed);
  EXPECT_NE(result.error.find("not a plain file name"), std::string::npos) << result.error;
}

TEST_F(JobRunnerTest, CancelStopsTheStageAtItsNextCheck) {
  bool cancel = false;
  int iterations_after_cancel = 0;
  bodies_["loop"] = [&](StageContext& context) {
    for (int i = 0; i < 1000; ++i) {
      if (cancel) ++iterations_after_cancel;
      context.check_canceled();
      if (i == 10) cancel = true;  // the server says "canceled" during iteration 10
    }
    return StageResult{};
  };
  add_recording_stage("after");
  spec_.stages = {"loop", "after"};
  std::vector<std::string> done;
  JobHooks hooks;
  hooks.canceled = [&] { return cancel; };
  hooks.on_stage_done = [&](const std::string& s, const StageResult&, double) {
    done.push_back(s);
  };

  const JobResult result = runner().run(spec_, hooks);

  EXPECT_EQ(result.outcome, JobOutcome::kCanceled);
  EXPECT_EQ(result.failed_stage, "loop");
  EXPECT_EQ(iterations_after_cancel, 1);  // stopped at the first check after the cancel
  EXPECT_TRUE(order_.empty());
  EXPECT_TRUE(done.empty());  // nothing more is reported
}

TEST_F(JobRunnerTest, CancelBeforeAStageStartsRunsNothing) {
  add_recording_stage("a");
  spec_.stages = {"a"};
  JobHooks hooks;
  hooks.canceled = [] { return true; };
  EXPECT_EQ(runner().run(spec_, hooks).outcome, JobOutcome::kCanceled);
  EXPECT_TRUE(order_.empty());
}

TEST_F(JobRunnerTest, ProgressIsMonotoneAndClamped) {
  bodies_["a"] = [](StageContext& context) {
    for (double p : {0.5, 0.3, std::numeric_limits<double>::quiet_NaN(), 0.8, 0.8, 2.0, -1.0})
      context.progress(p);
    return StageResult{};
  };
  bodies_["b"] = [](StageContext& context) {
    context.progress(0.25);
    return StageResult{};
  };
  spec_.stages = {"a", "b"};
  std::vector<std::pair<std::string, double>> seen;
  JobHooks hooks;
  hooks.progress = [&](const std::string& s, double p) { seen.emplace_back(s, p); };

  ASSERT_EQ(runner().run(spec_, hooks).outcome, JobOutcome::kSucceeded);

  const std::vector<std::pair<std::string, double>> expected = {
      {"a", 0.0}, {"a", 0.5}, {"a", 0.8}, {"a", 1.0}, {"b", 0.0}, {"b", 0.25}, {"b", 1.0}};
  EXPECT_EQ(seen, expected);
}

TEST_F(JobRunnerTest, StageLogLinesArePrefixedWithTheStageName) {
  bodies_["a"] = [](StageContext& context) {
    context.log("read 12 scans");
    return StageResult{};
  };
  spec_.stages = {"a"};
  std::vector<std::string> lines;
  JobHooks hooks;
  hooks.log = [&](const std::string& line) { lines.push_back(line); };
  ASSERT_EQ(runner().run(spec_, hooks).outcome, JobOutcome::kSucceeded);
  EXPECT_NE(std::find(lines.begin(), lines.end(), "a: read 12 scans"), lines.end());
}

TEST_F(JobRunnerTest, HookExceptionPropagatesInsteadOfFailingTheStage) {
  add_recording_stage("a");
  spec_.stages = {"a"};
  JobHooks hooks;
  hooks.on_stage_done = [](const std::string&, const StageResult&, double) {
    throw std::runtime_error("upload failed");
  };
  EXPECT_THROW(runner().run(spec_, hooks), std::runtime_error);
}

// A worker runs the job on its copy of the bundle, deep in its cache: errors name the files
// as the user's bundle does (issue 18), the CAD mesh by its own name.
TEST_F(JobRunnerTest, ErrorsNameFilesRelativeToTheMissionBundle) {
  spec_.mission_dir = dir_ / "cache" / "jobs" / "j_1" / "mission";
  keel::testing::write_tiny_mission(spec_.mission_dir);
  {
    std::ofstream imu(spec_.mission_dir / "imu.csv", std::ios::app);
    imu << "1700000000.2,0,0,0.1,0,0,9.81\n";  // line 8: a decreasing stamp
  }
  spec_.stages = {"ingest"};
  JobResult result = JobRunner(make_stage).run(spec_, {});
  EXPECT_EQ(result.outcome, JobOutcome::kFailed);
  EXPECT_EQ(result.error.rfind("ingest: imu.csv:8: ", 0), 0u) << result.error;

  keel::testing::write_tiny_mission(spec_.mission_dir);
  fs::create_directories(dir_ / "cache" / "jobs" / "j_1" / "cad");
  spec_.cad_path = dir_ / "cache" / "jobs" / "j_1" / "cad" / "hull.obj";
  std::ofstream(spec_.cad_path) << "v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n";
  result = JobRunner(make_stage).run(spec_, {});
  EXPECT_EQ(result.error.rfind("ingest: hull.obj:3: ", 0), 0u) << result.error;
}

}  // namespace
}  // namespace keel::pipeline
