// The exported URDF and MJCF (fivebar/export/urdf.hpp, fivebar/export/mjcf.hpp) checked by the client itself:
// MuJoCo 2.2.2 (Debian libmujoco-dev) loads every file `fivebar export` writes for the showcase
// (designs/iros2022.yaml) without edits, with closed-form masses and with STL meshes, and each
// station's bundle copied on its own; the keyframe `home` puts the tactors where mjcf_home() says,
// without contact; the upper tactor driven into the lower one meets it (contacts); a joint driven
// into its hard stop at full duty stays at it; the MJCF's
// loop closures sit at P (the anchor MuJoCo computes on the second body is P in that body's frame,
// known from the link lengths); the rotor inertia is in both files; and the same 100 Hz PID (the
// exported gains, potentiometers and ADC, zero-order hold, one period of delay) run in MuJoCo on
// the MJCF follows the joint angles of `fivebar simulate` (CVODE on fivebar's own equations of
// motion, fivebar/dynamics.hpp) on a 1 mm step and on the stretch pattern, a second formulation
// and integrator against the first.
//
// What limits the agreement: the MJCF neglects the winding's inductance (L/R = 0.1 ms; fivebar
// simulate integrates the current), MuJoCo's semi-implicit Euler at the file's 0.1 ms timestep,
// its frictionloss (a soft constraint) against simulate's tanh-smoothed Coulomb friction, and the
// connect constraints' softness (solref 0.2 ms, solimp 0.9999). The measured figures are printed
// (RecordProperty and stdout) and asserted more than ten times below the showcase's 0.11 mm tracking
// error.

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "fivebar/design.hpp"
#include "fivebar/dynamics.hpp"
#include "fivebar/export/export.hpp"
#include "fivebar/kinematics.hpp"
#include "fivebar/export/mjcf.hpp"
#include "fivebar/sections/geometry.hpp"
#include "fivebar/sections/patterns.hpp"
#include "fivebar/sections/print.hpp"
#include "fivebar/export/urdf.hpp"

namespace fivebar {
namespace {

namespace fs = std::filesystem;
const fs::path kSource = FIVEBAR_SOURCE_DIR;

#ifdef FIVEBAR_SANITIZE
constexpr bool kSanitized = true;  // the sanitizer build (FIVEBAR_SANITIZE): shorter runs
#else
constexpr bool kSanitized = false;
#endif

Design paper() { return load_design(kSource / "designs" / "iros2022.yaml"); }

struct TempDir {
  fs::path path;
  TempDir() {
    path = fs::temp_directory_path() / ("fivebar_mujoco_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

std::string read_text(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

/// A MuJoCo model loaded from a file, or the loader's error.
struct Loaded {
  mjModel* model = nullptr;
  std::string error;
  explicit Loaded(const fs::path& file) {
    char err[1000] = "";
    model = mj_loadXML(file.c_str(), nullptr, err, sizeof err);
    error = err;
  }
  ~Loaded() {
    if (model != nullptr) mj_deleteModel(model);
  }
  Loaded(const Loaded&) = delete;
  Loaded& operator=(const Loaded&) = delete;
};

int id_of(const mjModel* m, mjtObj type, const std::string& name) { return mj_name2id(m, type, name.c_str()); }

/// The showcase exported once (gate, both stations, URDF and MJCF, closed-form masses).
class MujocoTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    design_ = new Design(paper());
    dir_ = new fs::path(fs::temp_directory_path() / ("fivebar_mujoco_" + std::to_string(::getpid())));
    fs::remove_all(*dir_);
    ExportOptions options;
    options.urdf = true;
    options.mjcf = true;
    result_ = new ExportResult(export_controller(*design_, {ExportFormat::json}, *dir_ / "export", options));
  }
  static void TearDownTestSuite() {
    std::error_code ec;
    fs::remove_all(*dir_, ec);
    delete result_;
    delete dir_;
    delete design_;
  }
  static Design* design_;
  static fs::path* dir_;
  static ExportResult* result_;
};
Design* MujocoTest::design_ = nullptr;
fs::path* MujocoTest::dir_ = nullptr;
ExportResult* MujocoTest::result_ = nullptr;

// --- Loading --------------------------------------------------------------------------------------

TEST_F(MujocoTest, LoadsEveryExportedUrdfAndMjcfOfTheShowcaseWithoutEdits) {
  ASSERT_TRUE(result_->gate.passed());
  std::size_t urdf = 0, mjcf = 0;
  for (const fs::path& f : result_->files) {
    if (f.extension() != ".urdf" && f.extension() != ".xml") continue;
    SCOPED_TRACE(f.string());
    Loaded l(f);
    ASSERT_NE(l.model, nullptr) << l.error;
    EXPECT_EQ(l.error, "");
    // Per station: 4 motor joints and 4 elbows, every one a hinge; every moving body has mass.
    EXPECT_EQ(l.model->njnt, 8);
    for (int j = 0; j < l.model->njnt; ++j) EXPECT_EQ(l.model->jnt_type[j], mjJNT_HINGE);
    for (int b = 1; b < l.model->nbody; ++b) {
      if (l.model->body_jntnum[b] > 0) {
        EXPECT_GT(l.model->body_mass[b], 1e-6) << mj_id2name(l.model, mjOBJ_BODY, b);
      }
    }
    (f.extension() == ".urdf" ? urdf : mjcf) += 1;
  }
  EXPECT_EQ(urdf, 2u);  // index and thumb
  EXPECT_EQ(mjcf, 8u);  // per station: the model, its position variant and a scene of each
  // Each bundle copied on its own into a scratch folder loads as it is.
  for (const Station& s : design_->stations) {
    const fs::path alone = *dir_ / "alone" / s.name;
    fs::create_directories(alone.parent_path());
    fs::copy(*dir_ / "export" / ("iros2022_" + s.name), alone, fs::copy_options::recursive);
    for (const char* f : {"scene.xml", "scene_position.xml"}) {
      Loaded l(alone / f);
      EXPECT_NE(l.model, nullptr) << s.name << "/" << f << ": " << l.error;
      EXPECT_EQ(l.error, "");
    }
  }
}

TEST_F(MujocoTest, RotorInertiaIsTheArmatureOfTheMjcfAndTheTransmissionOfTheUrdf) {
  // The showcase's assumed motor: N = 200, J_r = 0.5 g cm^2 = 5e-8 kg m^2: N^2 J_r = 2e-3 kg m^2.
  const double reflected = 200.0 * 200.0 * 0.5e-7;
  for (const char* station : {"index", "thumb"}) {
    SCOPED_TRACE(station);
    Loaded l(*dir_ / "export" / (std::string("iros2022_") + station) / (std::string("iros2022_") + station + ".xml"));
    ASSERT_NE(l.model, nullptr) << l.error;
    ASSERT_EQ(l.model->nu, 4);
    for (const char* mech : {"lower", "upper"}) {
      for (int j = 1; j <= 2; ++j) {
        const std::string joint = joint_name(station, mech, j);
        const int id = id_of(l.model, mjOBJ_JOINT, joint);
        ASSERT_GE(id, 0) << joint;
        EXPECT_NEAR(l.model->dof_armature[l.model->jnt_dofadr[id]], reflected, 1e-18) << joint;
        EXPECT_NEAR(l.model->dof_damping[l.model->jnt_dofadr[id]], 1e-5, 1e-20);        // 0.01 mN m s/rad
        EXPECT_NEAR(l.model->dof_frictionloss[l.model->jnt_dofadr[id]], 5e-4, 1e-19);  // 0.5 mN m
        // The actuator: the torque-speed line, hand values of the assumed motor (eta 0.7, N 200,
        // k_t = k_e = 5 mN m/A, R 5 ohm, 6 V, 1 A): stall 0.7*200*0.005*6/5 = 0.84 N m, slope
        // -0.7*200^2*0.005^2/5 = -0.14 N m s/rad, clamp 0.7 N m.
        const int a = id_of(l.model, mjOBJ_ACTUATOR, joint);
        ASSERT_GE(a, 0);
        EXPECT_NEAR(l.model->actuator_gainprm[a * mjNGAIN], 0.84, 1e-12);
        // k_e = 0.5235987755982988 mV/rpm = 5.0000117 mV s/rad (the file's unit rounds 5 mV s/rad).
        EXPECT_NEAR(l.model->actuator_biasprm[a * mjNBIAS + 2], -0.14, 1e-6);
        EXPECT_NEAR(l.model->actuator_forcerange[2 * a + 1], 0.7, 1e-12);
        EXPECT_NEAR(l.model->actuator_ctrlrange[2 * a + 1], 1.0, 0.0);
        // No-load speed 6 V / (k_e N) = 6 rad/s: the line's zero.
        EXPECT_NEAR(l.model->actuator_gainprm[a * mjNGAIN] + l.model->actuator_biasprm[a * mjNBIAS + 2] * 6.0, 0.0, 1e-5);
      }
    }
    const std::string urdf = read_text(*dir_ / "export" / (std::string("iros2022_") + station + ".urdf"));
    EXPECT_NE(urdf.find("<mechanicalReduction>200</mechanicalReduction>"), std::string::npos);
    EXPECT_NE(urdf.find("<drake:rotor_inertia value=\"5e-08\"/>"), std::string::npos);
    EXPECT_NE(urdf.find("N^2 J_r = 0.002 kg m^2"), std::string::npos);
    // The velocity limit is the one joint speed: the motor's steady speed at 6 V less friction,
    // 5.996 rad/s (343.5 deg/s; test_urdf derives it), below the no-load 6 rad/s and the controller's 360 deg/s.
    const std::size_t v = urdf.find("velocity=\"");
    ASSERT_NE(v, std::string::npos);
    EXPECT_NEAR(std::stod(urdf.substr(v + 10)), 5.99599, 1e-5);
  }
}

TEST_F(MujocoTest, LoopClosuresSitAtTheTactorInBothBodies) {
  const Design& d = *design_;
  for (const Station& s : d.stations) {
    Loaded l(*dir_ / "export" / ("iros2022_" + s.name) / ("iros2022_" + s.name + ".xml"));
    ASSERT_NE(l.model, nullptr) << l.error;
    mjData* data = mj_makeData(l.model);
    mj_forward(l.model, data);
    for (const Mechanism* mech : s.mechanisms()) {
      SCOPED_TRACE(s.name + "/" + mech->name);
      const int e = id_of(l.model, mjOBJ_EQUALITY, s.name + "_" + mech->name + "_loop");
      ASSERT_GE(e, 0);
      const mjtNum* anchor = l.model->eq_data + e * mjNEQDATA;
      const int b1 = l.model->eq_obj1id[e], b2 = l.model->eq_obj2id[e];
      // body1 is the carrier, body2 the other distal link: their anchors are P at the ends of
      // L_carrier and L_other along their x axes (y = 0), from the design's lengths.
      const std::string n1 = mj_id2name(l.model, mjOBJ_BODY, b1), n2 = mj_id2name(l.model, mjOBJ_BODY, b2);
      const std::size_t c = n1.back() == '3' ? 2 : 3, o = 5 - c;
      EXPECT_NEAR(anchor[0], mech->L[c] * 1e-3, 1e-15);
      EXPECT_NEAR(anchor[1], 0.0, 1e-15);
      EXPECT_NEAR(anchor[3], mech->L[o] * 1e-3, 1e-12) << "MuJoCo's anchor on " << n2;
      EXPECT_NEAR(anchor[4], 0.0, 1e-12);
      // And qpos0 is the closed pose at the target centre: both anchors at the same world point,
      // the target's centre (mm -> m) in x and y.
      Eigen::Vector3d w1, w2;
      for (int k = 0; k < 3; ++k) {
        w1[k] = data->xpos[3 * b1 + k];
        w2[k] = data->xpos[3 * b2 + k];
        for (int i = 0; i < 3; ++i) {
          w1[k] += data->xmat[9 * b1 + 3 * k + i] * anchor[i];
          w2[k] += data->xmat[9 * b2 + 3 * k + i] * anchor[3 + i];
        }
      }
      EXPECT_NEAR((w1 - w2).norm(), 0.0, 1e-12);
      EXPECT_NEAR(w1.x(), s.target.center.x() * 1e-3, 1e-12);
      EXPECT_NEAR(w1.y(), s.target.center.y() * 1e-3, 1e-12);
    }
    mj_deleteData(data);
  }
}

/// A binary STL of the box [x0, x0 + a] x [y0, y0 + b] x [z0, z0 + c], outward normals.
void write_box(const fs::path& file, double x0, double y0, double z0, double a, double b, double c) {
  const std::array<std::array<double, 3>, 8> v{{{x0, y0, z0}, {x0 + a, y0, z0}, {x0 + a, y0 + b, z0}, {x0, y0 + b, z0},
                                                {x0, y0, z0 + c}, {x0 + a, y0, z0 + c}, {x0 + a, y0 + b, z0 + c}, {x0, y0 + b, z0 + c}}};
  const std::array<std::array<int, 3>, 12> f{{{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                                              {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}}};
  std::ofstream out(file, std::ios::binary);
  const std::string header(80, ' ');
  out.write(header.data(), 80);
  const std::uint32_t n = 12;
  out.write(reinterpret_cast<const char*>(&n), 4);
  for (const auto& t : f) {
    const float zero[3] = {0, 0, 0};
    out.write(reinterpret_cast<const char*>(zero), 12);
    for (int k : t) {
      const float p[3] = {float(v[std::size_t(k)][0]), float(v[std::size_t(k)][1]), float(v[std::size_t(k)][2])};
      out.write(reinterpret_cast<const char*>(p), 12);
    }
    const std::uint16_t attr = 0;
    out.write(reinterpret_cast<const char*>(&attr), 2);
  }
}

TEST(Mujoco, BundleLoadsAloneWithItsMeshesAndTheUrdfFromTheExportFolder) {
  // The layout of `fivebar run`: <out>/parts/<station>/*.stl, <out>/export/*.urdf naming
  // them "../parts/...". Boxes stand in for the renders.
  const Design d = paper();
  TempDir dir;
  fs::create_directories(dir.path / "parts" / "index");
  write_box(dir.path / "parts/index/link.stl", 0.5, -2.0, 0.0, 8.0, 4.0, 2.0);
  write_box(dir.path / "parts/index/tip.stl", -1.0, -1.0, 0.0, 2.0, 2.0, 1.0);
  write_box(dir.path / "parts/index/base.stl", -5.0, -5.0, -2.0, 30.0, 30.0, 2.0);
  Json parts = {{"parts", Json::array()}};
  parts["parts"].push_back({{"station", "index"}, {"uses", {"lower/L1", "lower/L2", "lower/L3", "lower/L4", "upper/L1",
                                                             "upper/L2", "upper/L3", "upper/L4"}},
                            {"stl", "index/link.stl"}});
  parts["parts"].push_back({{"station", "index"}, {"uses", {"lower/tactor", "upper/tactor"}}, {"stl", "index/tip.stl"}});
  parts["parts"].push_back({{"station", "index"}, {"uses", {"base"}}, {"stl", "index/base.stl"}});
  ExportOptions options;
  options.urdf = true;
  options.mjcf = true;
  options.stations = {"index"};
  options.urdf_options.parts = &parts;
  options.urdf_options.parts_dir = dir.path / "parts";
  const ExportResult r = export_controller(d, {}, dir.path / "export", options);
  ASSERT_TRUE(r.gate.passed());
  // The URDF names the renders in ../parts; the bundle carries copies in its assets/ folder and loads
  // from anywhere on its own (the export folder and the parts removed).
  const fs::path alone = dir.path / "elsewhere" / "copy";
  fs::create_directories(alone.parent_path());
  fs::copy(dir.path / "export" / "iros2022_index", alone, fs::copy_options::recursive);
  EXPECT_TRUE(fs::is_regular_file(alone / "assets/index/link.stl"));
  for (const fs::path& f : {dir.path / "export/iros2022_index.urdf", alone / "iros2022_index.xml",
                            alone / "iros2022_index_position.xml", alone / "scene.xml", alone / "scene_position.xml"}) {
    SCOPED_TRACE(f.string());
    if (f.extension() == ".xml" && fs::exists(dir.path / "export")) {
      fs::remove_all(dir.path / "export");
      fs::remove_all(dir.path / "parts");
    }
    if (f.extension() == ".urdf") {
      Loaded l(f);
      ASSERT_NE(l.model, nullptr) << l.error;
      EXPECT_EQ(l.model->nmesh, 3);
      continue;
    }
    Loaded l(f);
    ASSERT_NE(l.model, nullptr) << l.error;
    EXPECT_EQ(l.error, "");
    EXPECT_EQ(l.model->nmesh, 3);  // one asset per file: link, tip, base
    // The box link's mass from its STL (1.15 g/cm^3, 8 x 4 x 2 mm).
    const int b = id_of(l.model, mjOBJ_BODY, "index_upper_L1");
    ASSERT_GE(b, 0);
    EXPECT_NEAR(l.model->body_mass[b], 1.15e-6 * 64.0, 1e-12);
    EXPECT_EQ(l.model->nkey, 1);
    EXPECT_EQ(l.model->nu, 4);
  }
  for (const char* f : {"README.md", "LICENSE", "preview.svg"}) EXPECT_TRUE(fs::is_regular_file(alone / f)) << f;
  EXPECT_NE(read_text(alone / "README.md").find("![The home keyframe, top view](preview.svg)"), std::string::npos);
}

// --- The bundle: keyframe, contacts, stops, servos ------------------------------------------------

/// The index bundle's scene loaded (closed-form masses, box visuals), data at the keyframe `home`.
struct Scene {
  std::unique_ptr<Loaded> l;
  mjData* d = nullptr;
  explicit Scene(const fs::path& file) : l(std::make_unique<Loaded>(file)) {
    if (l->model == nullptr) return;
    d = mj_makeData(l->model);
    mj_resetDataKeyframe(l->model, d, mj_name2id(l->model, mjOBJ_KEY, "home"));
    mj_forward(l->model, d);
  }
  ~Scene() {
    if (d != nullptr) mj_deleteData(d);
  }
  Scene(const Scene&) = delete;
  Scene& operator=(const Scene&) = delete;
  mjModel* m() const { return l->model; }
  Vec2 tactor_mm(const std::string& name) const {
    const int a = l->model->sensor_adr[id_of(l->model, mjOBJ_SENSOR, name)];
    return Vec2(d->sensordata[a], d->sensordata[a + 1]) * 1e3;
  }
  std::string body_of_geom(int g) const { return mj_id2name(l->model, mjOBJ_BODY, l->model->geom_bodyid[g]); }
};

TEST_F(MujocoTest, HomeKeyframeHasTheTactorsApartAboutTheCentreAndNoContact) {
  for (const Station& s : design_->stations) {
    SCOPED_TRACE(s.name);
    for (const char* scene : {"scene.xml", "scene_position.xml"}) {
      Scene sc(*dir_ / "export" / ("iros2022_" + s.name) / scene);
      ASSERT_NE(sc.m(), nullptr) << sc.l->error;
      // The stretch pattern's start: 8 mm apart vertically about the target centre (designs/iros2022.yaml).
      const Vec2 lower = sc.tactor_mm(s.name + "_lower_tactor"), upper = sc.tactor_mm(s.name + "_upper_tactor");
      EXPECT_NEAR((lower - (s.target.center - Vec2(0.0, 4.0))).norm(), 0.0, 1e-9);
      EXPECT_NEAR((upper - (s.target.center + Vec2(0.0, 4.0))).norm(), 0.0, 1e-9);
      EXPECT_EQ(sc.d->ncon, 0) << "first contact: " << (sc.d->ncon > 0 ? sc.body_of_geom(sc.d->contact[0].geom1) + " / " +
                                                                           sc.body_of_geom(sc.d->contact[0].geom2)
                                                                     : "");
      // Held there by the position servos (ctrl = the home angles): still clear after 0.2 s.
      if (std::string(scene) == "scene_position.xml") {
        for (int i = 0; i < 2000; ++i) mj_step(sc.m(), sc.d);
        mj_forward(sc.m(), sc.d);
        EXPECT_EQ(sc.d->ncon, 0);
        EXPECT_NEAR((sc.tactor_mm(s.name + "_lower_tactor") - lower).norm(), 0.0, 0.01);
      }
    }
  }
}

TEST(Mujoco, HomeFallsBackToAReachableSeparation) {
  // A stretch pattern starting 100 mm apart (beyond the linkages' reach, L1 + L3 = 24 mm):
  // home falls back to the clearance rule, max(tactor 4, boss 5) + 0.3 = 5.3 mm, still without contact.
  Design d = paper();
  PatternSettings* p = d.get<PatternSettings>();
  ASSERT_NE(p, nullptr);
  for (PatternSpec& spec : p->global) spec.separation_mm = 100.0;
  p->overrides.clear();
  const Station& s = *d.station("index");
  const MjcfHome home = mjcf_home(d, s);
  EXPECT_DOUBLE_EQ(home.separation_mm, 5.3);
  EXPECT_EQ(home.separation_from, "max(tactor_diameter, boss_diameter) + min_clearance");
  TempDir dir;
  for (const BundleFile& f : mujoco_bundle(d, s)) {
    fs::create_directories((dir.path / f.path).parent_path());
    std::ofstream(dir.path / f.path, std::ios::binary) << f.bytes;
  }
  Scene sc(dir.path / "scene.xml");
  ASSERT_NE(sc.m(), nullptr) << sc.l->error;
  EXPECT_NEAR((sc.tactor_mm("index_upper_tactor") - sc.tactor_mm("index_lower_tactor")).norm(), 5.3, 1e-9);
  EXPECT_EQ(sc.d->ncon, 0);
}

TEST_F(MujocoTest, DrivingTheUpperTactorIntoTheLowerOneMakesContact) {
  const Station& s = *design_->station("index");
  Scene sc(*dir_ / "export/iros2022_index/scene_position.xml");
  ASSERT_NE(sc.m(), nullptr) << sc.l->error;
  // The upper mechanism's servos commanded to the lower tactor's point (the IK there, on the branch of
  // their home angles); the lower one holds home.
  const Vec2 target = sc.tactor_mm("index_lower_tactor");
  const Mechanism& upper = *s.mechanism("upper");
  const Pose ik_upper = ik(upper, target);
  ASSERT_NE(ik_upper.status, Status::unreachable);
  for (int j = 1; j <= 2; ++j) {
    const int a = id_of(sc.m(), mjOBJ_ACTUATOR, joint_name("index", "upper", j));
    const double th = j == 1 ? ik_upper.theta1 : ik_upper.theta2;
    const double home = sc.d->ctrl[a];
    sc.d->ctrl[a] = home + std::remainder(th - home, 2.0 * std::numbers::pi);
  }
  int contact_steps = 0;
  double deepest = 0.0, closest_mm = 1e9;
  std::string pair;
  for (int i = 0; i < 5000; ++i) {
    mj_step(sc.m(), sc.d);
    mj_forward(sc.m(), sc.d);
    closest_mm = std::min(closest_mm, (sc.tactor_mm("index_upper_tactor") - sc.tactor_mm("index_lower_tactor")).norm());
    bool between = false;
    for (int c = 0; c < sc.d->ncon; ++c) {
      const std::string b1 = sc.body_of_geom(sc.d->contact[c].geom1), b2 = sc.body_of_geom(sc.d->contact[c].geom2);
      if ((b1.rfind("index_upper", 0) == 0) != (b2.rfind("index_upper", 0) == 0)) {
        between = true;
        deepest = std::min(deepest, sc.d->contact[c].dist);
        if (pair.empty()) pair = b1 + " / " + b2;
      }
    }
    contact_steps += between ? 1 : 0;
  }
  std::printf("[ MuJoCo ] upper tactor driven into the lower: contact in %d of 5000 steps (first %s), deepest %.3g mm, "
              "tactors %.3g mm apart at the closest\n",
              contact_steps, pair.c_str(), -deepest * 1e3, closest_mm);
  EXPECT_GT(contact_steps, 0);
  EXPECT_GT(deepest, -0.5e-3);  // stiff contacts: less than half a millimetre of overlap
  // The bodies do not pass through each other: the bosses at the two P (5 mm, in the distal links'
  // common plane) keep the tactors a boss diameter apart, less the overlap; without contacts the
  // upper tactor reaches its command, the lower tactor's point.
  EXPECT_GT(closest_mm, 5.0 - 0.5);
}

TEST_F(MujocoTest, HardStopsHoldAtFullDuty) {
  // index_lower_theta1 runs down into its stop against the boss of lower O2 (19.38 deg, docs/urdf.md)
  // at full duty: by how much does it pass it?
  Scene sc(*dir_ / "export/iros2022_index/scene.xml");
  ASSERT_NE(sc.m(), nullptr) << sc.l->error;
  const int jid = id_of(sc.m(), mjOBJ_JOINT, "index_lower_theta1");
  ASSERT_EQ(sc.m()->jnt_limited[jid], 1);
  const double lo = sc.m()->jnt_range[2 * jid];
  EXPECT_NEAR(lo, std::acos(212.25 / 225.0), 1e-12);
  // {largest excursion past the stop, excursion after 1 s} in degrees, from home at full duty.
  const auto into_stop = [&]() {
    mj_resetDataKeyframe(sc.m(), sc.d, 0);
    sc.d->ctrl[id_of(sc.m(), mjOBJ_ACTUATOR, "index_lower_theta1")] = -1.0;
    double past = 0.0, held = 0.0;
    for (int i = 0; i < 10000; ++i) {
      mj_step(sc.m(), sc.d);
      const double q = sc.d->qpos[sc.m()->jnt_qposadr[jid]];
      past = std::max(past, lo - q);
      held = lo - q;
    }
    return std::array<double, 2>{past * 180.0 / std::numbers::pi, held * 180.0 / std::numbers::pi};
  };
  // As exported: the proximal link meets the other motor's boss (a contact) where its range ends.
  const auto file = into_stop();
  // The joint limit alone (contacts off), as exported and with MuJoCo's default limit softness
  // (solreflimit 0.02 1, solimplimit 0.9 0.95 0.001).
  sc.m()->opt.disableflags |= mjDSBL_CONTACT;
  const auto stiff = into_stop();
  const mjtNum soft_ref[2] = {0.02, 1.0}, soft_imp[5] = {0.9, 0.95, 0.001, 0.5, 2.0};
  for (int k = 0; k < 2; ++k) sc.m()->jnt_solref[mjNREF * jid + k] = soft_ref[k];
  for (int k = 0; k < 5; ++k) sc.m()->jnt_solimp[mjNIMP * jid + k] = soft_imp[k];
  const auto soft = into_stop();
  std::printf("[ MuJoCo ] full duty into the hard stop, deg past it at most / after 1 s: as exported %.3g / %.3g; the "
              "joint limit alone %.3g / %.3g; with MuJoCo's default limit softness %.3g / %.3g\n",
              file[0], file[1], stiff[0], stiff[1], soft[0], soft[1]);
  for (const auto& r : {file, stiff}) {
    EXPECT_LT(r[0], 0.5);
    EXPECT_LT(r[1], 0.1);
  }
  EXPECT_GT(soft[0], 5.0 * stiff[0]);
}

// --- The same controller in MuJoCo and in fivebar simulate ------------------------------------------

/// Joint angles and tactor positions at the controller's samples.
struct Trace {
  std::vector<std::vector<std::array<double, 2>>> theta;  ///< [sample][mechanism] rad
  std::vector<std::vector<Vec2>> P_mm;                     ///< [sample][mechanism]
  double max_loop_gap_m = 0.0;                             ///< the connect constraints' largest violation
  int max_contacts = 0;                                    ///< MuJoCo's contacts (fivebar simulate has none)
};

/// Departures from the exported model, to measure what limits the agreement.
struct Variant {
  bool quantise = true;        ///< the ADC in both
  double timestep_s = 0.0;     ///< MuJoCo's timestep; 0: the file's
  bool coulomb = true;         ///< Coulomb friction in both (false: none in either)
  double inductance_mH = 0.0;  ///< > 0: simulate's winding inductance instead of the motor's
  int integrator = -1;         ///< MuJoCo's integrator (mjINT_*); -1: the file's
};

/// `input` (its references, initial pose) under the exported PID in MuJoCo on the MJCF `file`:
/// at each sample t_k the potentiometers are read through the ADC (the exported calibration), the
/// PID's duty is computed and applied from t_k+1 (one period of delay), held over the period.
Trace run_mujoco(const fs::path& file, const SimulationInput& input, const Json& parameters, std::size_t samples,
                 const Variant& v) {
  Loaded l(file);
  EXPECT_NE(l.model, nullptr) << l.error;
  Trace tr;
  if (l.model == nullptr) return tr;
  mjModel* m = l.model;
  if (v.timestep_s > 0.0) m->opt.timestep = v.timestep_s;
  if (v.integrator >= 0) m->opt.integrator = v.integrator;
  if (!v.coulomb) {
    for (int i = 0; i < m->nv; ++i) m->dof_frictionloss[i] = 0.0;
  }
  mjData* d = mj_makeData(m);
  const Json& p = parameters.begin().value().at("ros__parameters");
  const double T = 1.0 / p.at("loop_rate_hz").get<double>();
  const int bits = p.at("adc").at("bits").get<int>();
  const std::array<double, 2> range{p.at("adc").at("range_v")[0].get<double>(), p.at("adc").at("range_v")[1].get<double>()};
  const auto substeps = static_cast<int>(std::lround(T / m->opt.timestep));
  EXPECT_NEAR(substeps * m->opt.timestep, T, 1e-12);

  struct Joint {
    int qpos = 0, sensor = 0, actuator = 0;
    Potentiometer pot;
    std::unique_ptr<DiscretePid> pid;
  };
  std::vector<std::array<Joint, 2>> joints(input.mechanisms.size());
  for (std::size_t k = 0; k < input.mechanisms.size(); ++k) {
    const SimulatedMechanism& sm = input.mechanisms[k];
    const Pose pose = fk(sm.model.mechanism, sm.theta0[0], sm.theta0[1]);
    const Vec2 r3 = pose.P - pose.A1, r4 = pose.P - pose.A2;
    const std::array<double, 2> phi{std::atan2(r3.y(), r3.x()), std::atan2(r4.y(), r4.x())};
    for (int j = 0; j < 2; ++j) {
      const std::string name = joint_name(input.station, sm.name, j + 1);
      Joint& jt = joints[k][std::size_t(j)];
      const int jid = id_of(m, mjOBJ_JOINT, name);
      EXPECT_GE(jid, 0) << name;
      jt.qpos = m->jnt_qposadr[jid];
      jt.sensor = m->sensor_adr[id_of(m, mjOBJ_SENSOR, name)];
      jt.actuator = id_of(m, mjOBJ_ACTUATOR, name);
      const Json& g = p.at("gains").at(name);
      PidGains gains;
      gains.kp = g.at("p").get<double>();
      gains.ki = g.at("i").get<double>();
      gains.kd = g.at("d").get<double>();
      gains.i_clamp = g.at("i_clamp").get<double>();
      jt.pid = std::make_unique<DiscretePid>(gains, T);
      jt.pot.volts_at_zero = p.at("potentiometers").at(name).at("volts_at_zero").get<double>();
      jt.pot.rad_per_volt = p.at("potentiometers").at(name).at("rad_per_volt").get<double>();
      d->qpos[jt.qpos] = sm.theta0[std::size_t(j)];
      // The elbow from FK, on the turn of its qpos0 (the file's ref).
      const int e = m->jnt_qposadr[id_of(m, mjOBJ_JOINT, input.station + "_" + sm.name + "_elbow" + std::to_string(j + 1))];
      const double rel = phi[std::size_t(j)] - sm.theta0[std::size_t(j)];
      const double turn = 2.0 * std::numbers::pi;
      d->qpos[e] = rel - turn * std::round((rel - m->qpos0[e]) / turn);
    }
  }
  mj_forward(m, d);
  std::vector<std::array<double, 2>> pending(input.mechanisms.size(), {0.0, 0.0});
  for (std::size_t s = 0; s < samples; ++s) {
    std::vector<std::array<double, 2>> th(input.mechanisms.size());
    std::vector<Vec2> P(input.mechanisms.size());
    for (std::size_t k = 0; k < input.mechanisms.size(); ++k) {
      const SimulatedMechanism& sm = input.mechanisms[k];
      const auto& ref = sm.reference[std::min(s, sm.reference.size() - 1)];
      for (std::size_t j = 0; j < 2; ++j) {
        Joint& jt = joints[k][j];
        th[k][j] = d->sensordata[jt.sensor];
        const double measured = v.quantise ? adc_reading(th[k][j], jt.pot, bits, range) : th[k][j];
        const double fresh = jt.pid->update(ref[j] - measured);
        d->ctrl[jt.actuator] = pending[k][j];
        pending[k][j] = fresh;
      }
      const int site = m->sensor_adr[id_of(m, mjOBJ_SENSOR, input.station + "_" + sm.name + "_tactor")];
      P[k] = Vec2(d->sensordata[site], d->sensordata[site + 1]) * 1e3;
    }
    tr.theta.push_back(th);
    tr.P_mm.push_back(P);
    for (int i = 0; i < substeps; ++i) {
      mj_step(m, d);
      for (int e = 0; e < m->neq; ++e) {
        // Loop gap: the two anchors' world points.
        const mjtNum* a = m->eq_data + e * mjNEQDATA;
        const int b1 = m->eq_obj1id[e], b2 = m->eq_obj2id[e];
        double gap2 = 0.0;
        for (int c = 0; c < 3; ++c) {
          double w1 = d->xpos[3 * b1 + c], w2 = d->xpos[3 * b2 + c];
          for (int r = 0; r < 3; ++r) {
            w1 += d->xmat[9 * b1 + 3 * c + r] * a[r];
            w2 += d->xmat[9 * b2 + 3 * c + r] * a[3 + r];
          }
          gap2 += (w1 - w2) * (w1 - w2);
        }
        tr.max_loop_gap_m = std::max(tr.max_loop_gap_m, std::sqrt(gap2));
      }
    }
    // mj_step computes the sensors before it integrates: recompute them at the new state, so the next
    // sample reads the joints at t_k+1 and not one timestep earlier.
    mj_forward(m, d);
    tr.max_contacts = std::max(tr.max_contacts, d->ncon);
  }
  mj_deleteData(d);
  return tr;
}

struct Agreement {
  double rad = 0.0;  ///< max |theta_mujoco - theta_simulate| over samples, joints, mechanisms
  double mm = 0.0;   ///< max |P_mujoco - P_simulate|
  double tracking_mm = 0.0;  ///< simulate's own max tracking error, for scale
};

Agreement compare(const SimulationResult& sim, const Trace& mj) {
  Agreement a;
  for (std::size_t s = 0; s < sim.samples.size() && s < mj.theta.size(); ++s) {
    for (std::size_t k = 0; k < sim.samples[s].mechanisms.size(); ++k) {
      const MechanismSample& ms = sim.samples[s].mechanisms[k];
      for (std::size_t j = 0; j < 2; ++j) a.rad = std::max(a.rad, std::abs(ms.theta[j] - mj.theta[s][k][j]));
      a.mm = std::max(a.mm, (ms.P_mm - mj.P_mm[s][k]).norm());
    }
  }
  for (const MechanismSummary& m : sim.summary) a.tracking_mm = std::max(a.tracking_mm, m.max_error_mm);
  return a;
}

/// simulate() and MuJoCo on the same input; the figures printed.
Agreement run_both(const Design& d, const fs::path& mjcf, const Json& parameters, SimulationInput input,
                   const std::string& label, double* loop_gap_m = nullptr, const Variant& v = {}) {
  SimulationOptions o;
  o.contact = false;  // the MJCF leaves the skin out (fivebar/export/mjcf.hpp)
  o.quantise = v.quantise;
  for (SimulatedMechanism& m : input.mechanisms) {
    for (MotorParams& p : m.model.motors) {
      if (!v.coulomb) p.coulomb_friction_mNm = 0.0;
      if (v.inductance_mH > 0.0) p.inductance_mH = v.inductance_mH;
    }
  }
  const SimulationResult sim = simulate(input, o);
  EXPECT_TRUE(sim.ok()) << sim.reason;
  const Trace mj = run_mujoco(mjcf, input, parameters, sim.samples.size(), v);
  EXPECT_EQ(mj.theta.size(), sim.samples.size());
  EXPECT_EQ(mj.max_contacts, 0) << "the links touch in MuJoCo: the comparison with fivebar simulate (no contacts) fails";
  const Agreement a = compare(sim, mj);
  std::printf("[ MuJoCo ] %s: %zu samples, MuJoCo vs fivebar simulate: max %.3g rad, %.3g mm (simulate's tracking error "
              "%.3g mm); loop gap %.3g m\n",
              label.c_str(), sim.samples.size(), a.rad, a.mm, a.tracking_mm, mj.max_loop_gap_m);
  ::testing::Test::RecordProperty(label + "_rad", std::to_string(a.rad));
  ::testing::Test::RecordProperty(label + "_mm", std::to_string(a.mm));
  if (loop_gap_m != nullptr) *loop_gap_m = mj.max_loop_gap_m;
  (void)d;
  return a;
}

std::map<std::string, MechanismInertia> closed_form(const Design& d, const std::string& station) {
  std::map<std::string, MechanismInertia> inertia;
  for (const Mechanism* m : d.require_station(station).mechanisms()) {
    inertia[m->name] = closed_form_inertia(*m, *d.get<Geometry>(), *d.get<PrintSettings>());
  }
  return inertia;
}

// The agreement bound asserted below: 10 um at the tactor, 11x under the showcase's 0.11 mm
// tracking error, and 1e-3 rad (measured 6.04e-4 rad and 4.93 um on the step, 3.45e-4 rad and
// 3.30 um on the stretch; printed, and quoted in docs/mjcf.md). The inductance the MJCF leaves out
// and MuJoCo's Euler step at 0.1 ms set it (WhatLimitsTheAgreement below).
constexpr double kAgreementMm = 1e-2;
constexpr double kAgreementRad = 1e-3;

TEST_F(MujocoTest, AOneMillimetreStepFollowsFivebarSimulate) {
  const Design& d = *design_;
  SimulationRequest request;
  request.station = "index";
  request.step = true;
  if (kSanitized) request.step_hold_s = 0.15;
  std::vector<SimulationInput> inputs = simulation_inputs(d, request, closed_form(d, "index"));
  ASSERT_EQ(inputs.size(), 1u);
  double gap = 0.0;
  const Agreement a = run_both(d, *dir_ / "export/iros2022_index/iros2022_index.xml", result_->parameters, inputs[0], "step", &gap);
  EXPECT_GT(a.tracking_mm, 0.5);  // the step is tracked with a transient of most of a millimetre
  EXPECT_LT(a.rad, kAgreementRad);
  EXPECT_LT(a.mm, kAgreementMm);
  EXPECT_LT(gap, 1e-6);  // the loops stay closed to a micrometre
}

TEST_F(MujocoTest, TheStretchPatternFollowsFivebarSimulate) {
  const Design& d = *design_;
  SimulationRequest request;
  request.station = "index";
  request.pattern = PatternKind::stretch;
  std::vector<SimulationInput> inputs = simulation_inputs(d, request, closed_form(d, "index"));
  ASSERT_EQ(inputs.size(), 1u);
  SimulationInput& in = inputs[0];
  if (kSanitized) {
    for (SimulatedMechanism& m : in.mechanisms) {
      m.reference.resize(30);
      m.reference_point_mm.resize(30);
      if (!m.target_mm.empty()) m.target_mm.resize(30);  // what the runtime is fed (fivebar/dynamics.hpp)
    }
  }
  const Agreement a = run_both(d, *dir_ / "export/iros2022_index/iros2022_index.xml", result_->parameters, in, "stretch");
  EXPECT_GT(a.tracking_mm, 0.0);
  EXPECT_LT(a.rad, kAgreementRad);
  EXPECT_LT(a.mm, kAgreementMm);
}

TEST_F(MujocoTest, WhatLimitsTheAgreement) {
  const Design& d = *design_;
  SimulationRequest request;
  request.station = "index";
  request.step = true;
  if (kSanitized) request.step_hold_s = 0.15;
  const SimulationInput in = simulation_inputs(d, request, closed_form(d, "index")).front();
  const fs::path f = *dir_ / "export/iros2022_index/iros2022_index.xml";
  const Json& p = result_->parameters;
  struct Row {
    const char* label;
    Variant v;
  };
  // Measured, not asserted: each departure alone (printed; docs/mjcf.md quotes them).
  const std::vector<Row> rows{
      {"step_no_adc", {.quantise = false}},
      {"step_no_adc_no_coulomb", {.quantise = false, .coulomb = false}},
      {"step_no_adc_dt1e-5", {.quantise = false, .timestep_s = 1e-5}},
  };
  for (const Row& r : rows) run_both(d, f, p, in, r.label, nullptr, r.v);
  // The models agree once what the MJCF leaves out is left out of simulate too (an inductance of
  // 1e-4 mH: L/R = 20 ns) and MuJoCo steps finely: then the difference is MuJoCo's semi-implicit
  // Euler, first order in the timestep (a tenth of the step, a tenth of the difference).
  const Variant ideal{.quantise = false, .coulomb = false, .inductance_mH = 1e-4};
  Variant fine = ideal;
  fine.timestep_s = 1e-5;
  const Agreement coarse_a = run_both(d, f, p, in, "step_ideal_dt1e-4", nullptr, ideal);
  const Agreement fine_a = run_both(d, f, p, in, "step_ideal_dt1e-5", nullptr, fine);
  EXPECT_LT(fine_a.rad, 6e-5);
  EXPECT_GT(coarse_a.rad / fine_a.rad, 5.0);
  EXPECT_LT(coarse_a.rad / fine_a.rad, 20.0);
}

}  // namespace
}  // namespace fivebar
