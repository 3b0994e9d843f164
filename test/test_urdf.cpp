// Tests of the URDF (fivebar/export/urdf.hpp): urdfdom's check_urdf accepts the showcase's files; the
// document read back by a small XML reader written here has the tree, joint limits, masses and
// ros2_control block the design gives, compared with hand values (the hard stop's angle, the
// potentiometer's end, the stall torque) and with an independent closed-form mass of a slab; with
// a parts report of box-shaped STL files written here, masses, centres and inertias are the
// boxes' and the meshes are the visuals; export_controller writes one URDF per station.

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "fivebar/design.hpp"
#include "fivebar/error.hpp"
#include "fivebar/export/export.hpp"
#include "fivebar/device/joint_limits.hpp"
#include "fivebar/sections/geometry.hpp"
#include "fivebar/export/ros2_package.hpp"
#include "fivebar/export/urdf.hpp"

namespace fivebar {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

const fs::path kSource = FIVEBAR_SOURCE_DIR;
constexpr double kPi = std::numbers::pi;
double deg(double d) { return d * kPi / 180.0; }
const char* const kCheckUrdf = "/usr/bin/check_urdf";

Design paper() { return load_design(kSource / "designs" / "iros2022.yaml"); }

// --- A minimal XML reader: elements, attributes, text; comments, declarations skipped -----------

struct Element {
  std::string name;
  std::map<std::string, std::string> attributes;
  std::vector<std::unique_ptr<Element>> children;
  std::string text;
  const Element* child(const std::string& n) const {
    for (const auto& c : children)
      if (c->name == n) return c.get();
    return nullptr;
  }
  std::vector<const Element*> all(const std::string& n) const {
    std::vector<const Element*> out;
    for (const auto& c : children)
      if (c->name == n) out.push_back(c.get());
    return out;
  }
  const std::string& at(const std::string& key) const {
    const auto it = attributes.find(key);
    if (it == attributes.end()) throw std::runtime_error("<" + name + "> has no attribute " + key);
    return it->second;
  }
};

class XmlReader {
 public:
  explicit XmlReader(std::string text) : s_(std::move(text)) {}
  std::unique_ptr<Element> document() {
    skip_misc();
    auto root = element();
    skip_misc();
    if (i_ != s_.size()) fail("content after the root element");
    return root;
  }

 private:
  std::string s_;
  std::size_t i_ = 0;
  [[noreturn]] void fail(const std::string& why) { throw std::runtime_error("XML at " + std::to_string(i_) + ": " + why); }
  bool starts(const char* p) const { return s_.compare(i_, std::strlen(p), p) == 0; }
  void space() {
    while (i_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[i_]))) ++i_;
  }
  void skip_misc() {
    for (;;) {
      space();
      if (starts("<!--")) {
        const std::size_t end = s_.find("-->", i_ + 4);
        if (end == std::string::npos) fail("unterminated comment");
        if (s_.substr(i_ + 4, end - i_ - 4).find("--") != std::string::npos) fail("-- inside a comment");
        i_ = end + 3;
      } else if (starts("<?")) {
        const std::size_t end = s_.find("?>", i_);
        if (end == std::string::npos) fail("unterminated declaration");
        i_ = end + 2;
      } else {
        return;
      }
    }
  }
  std::string name() {
    const std::size_t b = i_;
    while (i_ < s_.size() && (std::isalnum(static_cast<unsigned char>(s_[i_])) || s_[i_] == '_' || s_[i_] == ':' || s_[i_] == '-')) ++i_;
    if (b == i_) fail("expected a name");
    return s_.substr(b, i_ - b);
  }
  static std::string unescape(const std::string& t) {
    std::string out;
    for (std::size_t k = 0; k < t.size(); ++k) {
      if (t[k] != '&') {
        out += t[k];
        continue;
      }
      const std::size_t e = t.find(';', k);
      const std::string ent = t.substr(k, e - k + 1);
      out += ent == "&amp;" ? "&" : ent == "&lt;" ? "<" : ent == "&gt;" ? ">" : ent == "&quot;" ? "\"" : "'";
      k = e;
    }
    return out;
  }
  std::unique_ptr<Element> element() {
    if (!starts("<")) fail("expected <");
    ++i_;
    auto e = std::make_unique<Element>();
    e->name = name();
    for (;;) {
      space();
      if (starts("/>")) {
        i_ += 2;
        return e;
      }
      if (starts(">")) {
        ++i_;
        break;
      }
      const std::string key = name();
      space();
      if (!starts("=")) fail("expected =");
      ++i_;
      space();
      const char q = s_[i_];
      if (q != '"' && q != '\'') fail("expected a quoted value");
      const std::size_t end = s_.find(q, i_ + 1);
      if (!e->attributes.emplace(key, unescape(s_.substr(i_ + 1, end - i_ - 1))).second) fail("duplicate attribute " + key);
      i_ = end + 1;
    }
    for (;;) {
      skip_misc();
      if (starts("</")) {
        i_ += 2;
        if (name() != e->name) fail("mismatched end tag of " + e->name);
        space();
        if (!starts(">")) fail("expected >");
        ++i_;
        return e;
      }
      if (starts("<")) {
        e->children.push_back(element());
      } else {
        const std::size_t b = i_;
        while (i_ < s_.size() && s_[i_] != '<') ++i_;
        e->text += unescape(s_.substr(b, i_ - b));
      }
    }
  }
};

double number(const std::string& t) { return std::stod(t); }
std::array<double, 3> triple(const std::string& t) {
  std::istringstream in(t);
  std::array<double, 3> v{};
  in >> v[0] >> v[1] >> v[2];
  return v;
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

struct TempDir {
  fs::path path;
  TempDir() {
    path = fs::temp_directory_path() / ("fivebar_urdf_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

std::string run(const std::string& command) {
  std::string out;
  FILE* pipe = ::popen(command.c_str(), "r");
  if (pipe == nullptr) return out;
  std::array<char, 4096> buffer{};
  std::size_t n;
  while ((n = std::fread(buffer.data(), 1, buffer.size(), pipe)) > 0) out.append(buffer.data(), n);
  const int status = ::pclose(pipe);
  out += "\n[exit " + std::to_string(WEXITSTATUS(status)) + "]";
  return out;
}

const Element* find_named(const Element& robot, const std::string& tag, const std::string& name) {
  for (const Element* e : robot.all(tag))
    if (e->at("name") == name) return e;
  return nullptr;
}

// --- Tests -------------------------------------------------------------------------------------

TEST(Urdf, CheckUrdfAcceptsTheShowcase) {
  if (!fs::exists(kCheckUrdf)) GTEST_SKIP() << "check_urdf not installed (Debian package liburdfdom-tools): not run";
  const Design d = paper();
  TempDir dir;
  for (const Station& s : d.stations) {
    const fs::path file = dir.path / urdf_file_name(d, s);
    std::ofstream(file) << render_urdf(d, s);
    const std::string out = run(std::string(kCheckUrdf) + " '" + file.string() + "' 2>&1");
    SCOPED_TRACE(out);
    EXPECT_THAT(out, HasSubstr("robot name is: iros2022_" + s.name));
    EXPECT_THAT(out, HasSubstr("Successfully Parsed XML"));
    EXPECT_THAT(out, HasSubstr("root Link: " + s.name + "_base has 4 child(ren)"));
    EXPECT_THAT(out, HasSubstr("[exit 0]"));
  }
}

TEST(Urdf, TreeLimitsMassesAndRos2ControlMatchTheDesign) {
  const Design d = paper();
  const Station& s = *d.station("index");
  const std::string text = render_urdf(d, s);
  const auto robot = XmlReader(text).document();
  ASSERT_EQ(robot->name, "robot");
  EXPECT_EQ(robot->at("name"), "iros2022_index");

  // A tree: every link but the root is the child of exactly one joint; 4 motor joints, 4 elbows,
  // 2 fixed tips and 2 fixed cut frames P (no massless link on a moving joint: MuJoCo refuses one).
  std::map<std::string, int> parents;
  for (const Element* l : robot->all("link")) parents[l->at("name")] = 0;
  EXPECT_EQ(parents.size(), 1u + 2 * 6);  // base + per mechanism L1..L4, tip, P
  std::map<std::string, int> types;
  for (const Element* j : robot->all("joint")) {
    ++types[j->at("type")];
    ASSERT_TRUE(parents.count(j->child("child")->at("link")));
    ASSERT_TRUE(parents.count(j->child("parent")->at("link")));
    ++parents[j->child("child")->at("link")];
  }
  for (const auto& [link, n] : parents) EXPECT_EQ(n, link == "index_base" ? 0 : 1) << link;
  EXPECT_EQ(types["revolute"], 4);
  EXPECT_EQ(types["continuous"], 4);
  EXPECT_EQ(types["fixed"], 4);
  for (const Element* j : robot->all("joint")) {
    if (j->at("type") == "fixed") continue;
    const Element* child = find_named(*robot, "link", j->child("child")->at("link"));
    ASSERT_NE(child->child("inertial"), nullptr) << j->at("name") << " moves a link without mass";
    EXPECT_GT(number(child->child("inertial")->child("mass")->at("value")), 0.0);
  }
  // The cut: P on L4 (L3 carries the post), at L4's length, one plane up (L3's plane).
  const Element* cut = find_named(*robot, "joint", "index_lower_P_mount");
  ASSERT_NE(cut, nullptr);
  EXPECT_EQ(cut->child("parent")->at("link"), "index_lower_L4");
  EXPECT_DOUBLE_EQ(triple(cut->child("origin")->at("xyz"))[0], 0.015);

  // Motor joints: limits = the usable ranges, by hand: the boss of the other motor 19.38 deg
  // (cos = 212.25 / 225) and the potentiometer's end 285 deg (0.25 V offset, 60 deg/V, 300 deg).
  const double stop = std::acos(212.25 / 225.0);
  const Element* t1 = find_named(*robot, "joint", "index_lower_theta1");
  ASSERT_NE(t1, nullptr);
  EXPECT_EQ(t1->at("type"), "revolute");
  const Element* lim = t1->child("limit");
  EXPECT_NEAR(number(lim->at("lower")), stop, 1e-15);
  EXPECT_NEAR(number(lim->at("upper")), deg(285), 1e-15);
  // The one joint speed (fivebar/device/joint_limits.hpp): the motor's steady speed at the output
  // at 6 V less friction, (eta N k_t V / R - tau_c) / (eta N^2 k_t k_e / R + b) with k_e N =
  // 0.5236 mV/rpm x 200 = 1.0000 V s/rad: (0.84 - 0.0005) / (0.14 + 0.00001) = 5.996 rad/s
  // (343.5 deg/s), below the no-load 6 rad/s and controller.max_velocity_deg_s 360.
  const double ke_n = 0.5236e-3 * 60.0 / (2.0 * std::numbers::pi) * 200.0;
  EXPECT_NEAR(number(lim->at("velocity")), (0.7 * 200 * 0.005 * 6.0 / 5.0 - 0.5e-3) / (0.7 * 200 * 0.005 * ke_n / 5.0 + 1e-5), 1e-12);
  // Stall torque at the output: eta N k_t min(V / R, I_max) = 0.7 x 200 x 5 mN m/A x min(6/5, 1) A.
  EXPECT_NEAR(number(lim->at("effort")), 0.7 * 200 * 0.005 * 1.0, 1e-15);
  EXPECT_EQ(triple(t1->child("origin")->at("xyz"))[0], 0.0);
  EXPECT_EQ(triple(find_named(*robot, "joint", "index_lower_theta2")->child("origin")->at("xyz"))[0], 0.0125);
  for (const Mechanism* m : s.mechanisms()) {
    const auto ranges = usable_ranges(d, s, *m);
    for (const UsableRange& r : ranges) {
      const Element* j = find_named(*robot, "joint", r.joint);
      ASSERT_NE(j, nullptr) << r.joint;
      EXPECT_EQ(number(j->child("limit")->at("lower")), r.lo);
      EXPECT_EQ(number(j->child("limit")->at("upper")), r.hi);
    }
  }
  const Element* elbow = find_named(*robot, "joint", "index_upper_elbow2");
  ASSERT_NE(elbow, nullptr);
  EXPECT_EQ(elbow->at("type"), "continuous");
  EXPECT_EQ(elbow->child("parent")->at("link"), "index_upper_L2");
  // From L2's frame: 9 mm along x, one plane up (2.5 mm plate + 0.4 mm gap).
  const auto e = triple(elbow->child("origin")->at("xyz"));
  EXPECT_DOUBLE_EQ(e[0], 0.009);
  EXPECT_NEAR(e[2], 0.0029, 1e-15);
  EXPECT_THAT(text, HasSubstr("fills the passive elbows from forward kinematics"));
  // The gearing and the rotor inertia: a transmission per motor joint, N = 200, J_r = 0.5 g cm^2.
  const auto transmissions = robot->all("transmission");
  ASSERT_EQ(transmissions.size(), 4u);
  for (const Element* tr : transmissions) {
    EXPECT_EQ(tr->child("type")->text, "transmission_interface/SimpleTransmission");
    const Element* act = tr->child("actuator");
    ASSERT_NE(act, nullptr);
    EXPECT_EQ(act->at("name"), tr->child("joint")->at("name") + "_motor");
    EXPECT_EQ(number(act->child("mechanicalReduction")->text), 200.0);
    EXPECT_DOUBLE_EQ(number(act->child("drake:rotor_inertia")->at("value")), 0.5e-7);
  }
  EXPECT_THAT(text, HasSubstr("reflected rotor inertia N^2 J_r = 0.002 kg m^2"));
  // The transmissions declare the interface ros2_control commands: position (the device runs its PID).
  for (const Element* tr : transmissions) {
    EXPECT_EQ(tr->child("joint")->child("hardwareInterface")->text, "hardware_interface/PositionJointInterface");
    EXPECT_EQ(tr->child("actuator")->child("hardwareInterface")->text, "hardware_interface/PositionJointInterface");
  }

  // The base carries the base plate's inertia (SDFormat drops a root without one): by hand, the base
  // joints' bounding box 12.5 x 31 mm grown by the motor radius 5 and the margin 2 mm each side,
  // 3 mm thick, 1.15 g/cm^3, centred under the joints.
  const Element* base = find_named(*robot, "link", "index_base");
  ASSERT_NE(base->child("inertial"), nullptr);
  EXPECT_NEAR(number(base->child("inertial")->child("mass")->at("value")), 1.15e-6 * 26.5 * 45.0 * 3.0, 1e-15);
  const auto base_com = triple(base->child("inertial")->child("origin")->at("xyz"));
  EXPECT_NEAR(base_com[0], 0.00625, 1e-15);
  EXPECT_NEAR(base_com[1], 0.0155, 1e-15);
  EXPECT_NEAR(base_com[2], -0.0015, 1e-15);
  EXPECT_NEAR(number(base->child("inertial")->child("inertia")->at("izz")),
              1.15e-6 * 26.5 * 45.0 * 3.0 * (26.5 * 26.5 + 45.0 * 45.0) / 12.0 * 1e-6, 1e-15);

  // Masses: the distal link without the post (L4) is a 15 x 4 x 2.5 mm slab with a half disc of
  // 2.5 mm at each end, less two pin holes of 2 + 2 x 0.15 mm, at 1.15 g/cm^3.
  const double slab_mm3 = 15.0 * 4.0 * 2.5 + kPi * 2.5 * 2.5 * 2.5 - 2.0 * kPi * 1.15 * 1.15 * 2.5;
  const Element* l4 = find_named(*robot, "link", "index_lower_L4");
  ASSERT_NE(l4, nullptr);
  EXPECT_NEAR(number(l4->child("inertial")->child("mass")->at("value")), 1.15e-6 * slab_mm3, 1e-15);
  // Its centre of mass is midway (symmetric), in the plate's mid-plane.
  const auto com = triple(l4->child("inertial")->child("origin")->at("xyz"));
  EXPECT_NEAR(com[0], 0.0075, 1e-15);
  EXPECT_NEAR(com[2], 0.00125, 1e-15);
  // Every inertia is a physical one: positive, and each principal moment at most the sum of the others.
  for (const Element* l : robot->all("link")) {
    const Element* in = l->child("inertial");
    if (in == nullptr) continue;
    const Element* I = in->child("inertia");
    const double xx = number(I->at("ixx")), yy = number(I->at("iyy")), zz = number(I->at("izz"));
    EXPECT_GT(number(in->child("mass")->at("value")), 0.0);
    EXPECT_GT(xx, 0.0);
    EXPECT_LE(zz, xx + yy) << l->at("name");
    EXPECT_LE(xx, yy + zz) << l->at("name");
  }
  EXPECT_THAT(text, HasSubstr("closed_form_inertia()"));  // no parts report: says so

  // ros2_control: one system, the four motor joints, position command (min/max = the limits),
  // position and velocity states.
  const Element* rc = robot->child("ros2_control");
  ASSERT_NE(rc, nullptr);
  EXPECT_EQ(rc->at("type"), "system");
  EXPECT_EQ(rc->child("hardware")->child("plugin")->text, "mock_components/GenericSystem");
  const auto joints = rc->all("joint");
  ASSERT_EQ(joints.size(), 4u);
  EXPECT_EQ(joints[0]->at("name"), "index_lower_theta1");
  EXPECT_EQ(joints[3]->at("name"), "index_upper_theta2");
  for (const Element* j : joints) {
    const Element* command = j->child("command_interface");
    ASSERT_NE(command, nullptr);
    EXPECT_EQ(command->at("name"), "position");
    const Element* motor = find_named(*robot, "joint", j->at("name"));
    const auto params = command->all("param");
    ASSERT_EQ(params.size(), 2u);
    EXPECT_EQ(number(params[0]->text), number(motor->child("limit")->at("lower")));
    EXPECT_EQ(number(params[1]->text), number(motor->child("limit")->at("upper")));
    const auto states = j->all("state_interface");
    ASSERT_EQ(states.size(), 2u);
    EXPECT_EQ(states[0]->at("name"), "position");
    EXPECT_EQ(states[1]->at("name"), "velocity");
    const double initial = number(states[0]->child("param")->text);
    EXPECT_GT(initial, number(params[0]->text));
    EXPECT_LT(initial, number(params[1]->text));
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

TEST(Urdf, FromStlRendersMassesAreTheBoxesAndMeshesAreVisuals) {
  const Design d = paper();
  const Station& s = *d.station("index");
  TempDir dir;
  fs::create_directories(dir.path / "parts" / "index");
  // Boxes with exactly representable corners (floats): 8 x 4 x 2 mm links, a 2 x 2 x 1 mm tip.
  write_box(dir.path / "parts/index/link.stl", 0.5, -2.0, 0.0, 8.0, 4.0, 2.0);
  write_box(dir.path / "parts/index/tip.stl", -1.0, -1.0, 0.0, 2.0, 2.0, 1.0);
  Json parts = {{"parts", Json::array()}};
  parts["parts"].push_back({{"station", "index"}, {"uses", {"lower/L1", "lower/L2", "lower/L3", "lower/L4", "upper/L1",
                                                             "upper/L2", "upper/L3", "upper/L4"}},
                            {"stl", "index/link.stl"}});
  parts["parts"].push_back({{"station", "index"}, {"uses", {"lower/tactor", "upper/tactor"}}, {"stl", "index/tip.stl"}});
  UrdfOptions options;
  options.parts = &parts;
  options.parts_dir = dir.path / "parts";
  const std::string text = render_urdf(d, s, options);
  const auto robot = XmlReader(text).document();
  const Element* l1 = find_named(*robot, "link", "index_upper_L1");
  ASSERT_NE(l1, nullptr);
  const double rho = 1.15e-6;  // kg/mm^3
  const double mass = rho * 8.0 * 4.0 * 2.0;
  EXPECT_NEAR(number(l1->child("inertial")->child("mass")->at("value")), mass, 1e-12 * mass);
  const auto com = triple(l1->child("inertial")->child("origin")->at("xyz"));
  EXPECT_NEAR(com[0], 0.0045, 1e-15);
  EXPECT_NEAR(com[1], 0.0, 1e-15);
  EXPECT_NEAR(com[2], 0.001, 1e-15);
  // Box about its centre: m (b^2 + c^2) / 12 etc., kg mm^2 -> kg m^2.
  const Element* I = l1->child("inertial")->child("inertia");
  EXPECT_NEAR(number(I->at("ixx")), mass * (16.0 + 4.0) / 12.0 * 1e-6, 1e-9 * mass * 1e-6);
  EXPECT_NEAR(number(I->at("iyy")), mass * (64.0 + 4.0) / 12.0 * 1e-6, 1e-9 * mass * 1e-6);
  EXPECT_NEAR(number(I->at("izz")), mass * (64.0 + 16.0) / 12.0 * 1e-6, 1e-9 * mass * 1e-6);
  EXPECT_NEAR(number(I->at("ixy")), 0.0, 1e-12 * mass * 1e-6);
  const Element* tip = find_named(*robot, "link", "index_lower_tip");
  EXPECT_NEAR(number(tip->child("inertial")->child("mass")->at("value")), rho * 4.0, 1e-12);
  const Element* mesh = l1->child("visual")->child("geometry")->child("mesh");
  EXPECT_EQ(mesh->at("filename"), "../parts/index/link.stl");
  EXPECT_EQ(mesh->at("scale"), "0.001 0.001 0.001");
  EXPECT_THAT(text, HasSubstr("STL renders"));

  // A report without every piece (no tip): the closed form, and the URDF says why.
  parts["parts"].erase(1);
  const std::string fallback = render_urdf(d, s, options);
  EXPECT_THAT(fallback, HasSubstr("The parts report could not be used"));
  EXPECT_THAT(fallback, HasSubstr("closed_form_inertia()"));
}

TEST(Urdf, ExportWritesOneUrdfPerStationAtomicallyAndOnlyWhenAsked) {
  const Design d = paper();
  TempDir dir;
  ExportOptions options;
  options.stations = {"thumb"};
  options.urdf = true;
  const ExportResult r = export_controller(d, {ExportFormat::ros2}, dir.path / "out", options);
  ASSERT_TRUE(r.gate.passed());
  ASSERT_EQ(r.files.size(), 2u);
  EXPECT_EQ(r.files[1].filename(), "iros2022_thumb.urdf");
  const std::string text = slurp(r.files[1]);
  EXPECT_NO_THROW(XmlReader(text).document());
  EXPECT_EQ(text, render_urdf(d, *d.station("thumb")));
  for (const auto& entry : fs::directory_iterator(dir.path / "out")) {
    EXPECT_NE(entry.path().filename().string().front(), '.') << "temporary left: " << entry.path();
  }
  options.urdf = false;
  const ExportResult none = export_controller(d, {ExportFormat::ros2}, dir.path / "out2", options);
  ASSERT_EQ(none.files.size(), 1u);
  // No geometry: no URDF (and the controller files still go out for a one-mechanism station).
  Design bare = d;
  bare.reset<Geometry>();
  EXPECT_THROW(render_urdf(bare, *bare.station("index")), InputError);
}

// --- SDFormat (Gazebo's reader) --------------------------------------------------------------------

const char* const kIgn = "/usr/bin/ign";

/// `ign sdf -p FILE` (stdout only) parsed; nullptr and the text when it is not XML.
std::unique_ptr<Element> sdf_of(const fs::path& file, std::string& raw) {
  raw = run(std::string(kIgn) + " sdf -p '" + file.string() + "' 2>/dev/null");
  const std::size_t end = raw.rfind("\n[exit ");
  try {
    return XmlReader(raw.substr(0, end)).document();
  } catch (const std::exception&) {
    return nullptr;
  }
}

/// Every link of the URDF with mass is an SDF link, every joint but the massless cut's mount an SDF
/// joint of the same type, parent and child, and each cut frame P an SDF frame on its distal link at
/// the mount's origin.
void expect_sdformat_keeps(const fs::path& file) {
  SCOPED_TRACE(file.string());
  const auto urdf = XmlReader(slurp(file)).document();
  std::string raw;
  const auto sdf = sdf_of(file, raw);
  ASSERT_NE(sdf, nullptr) << raw;
  const Element* model = sdf->child("model");
  ASSERT_NE(model, nullptr) << raw;
  EXPECT_EQ(model->at("name"), urdf->at("name"));
  std::size_t massive = 0, cut = 0;
  for (const Element* l : urdf->all("link")) {
    const std::string name = l->at("name");
    if (name == "world") continue;
    if (l->child("inertial") != nullptr) {
      ++massive;
      EXPECT_NE(find_named(*model, "link", name), nullptr) << "link " << name << " lost";
    } else {
      ++cut;
      const Element* frame = find_named(*model, "frame", name);
      ASSERT_NE(frame, nullptr) << "frame " << name << " lost";
      // At the mount's origin on the mount's parent link.
      for (const Element* j : urdf->all("joint")) {
        if (j->child("child")->at("link") != name) continue;
        EXPECT_EQ(frame->at("attached_to"), j->child("parent")->at("link"));
        const auto a = triple(j->child("origin")->at("xyz"));
        std::istringstream pose(frame->child("pose")->text);
        std::array<double, 3> b{};
        pose >> b[0] >> b[1] >> b[2];
        for (std::size_t k = 0; k < 3; ++k) EXPECT_NEAR(a[k], b[k], 1e-12);
      }
    }
  }
  EXPECT_EQ(model->all("link").size(), massive);
  EXPECT_GT(cut, 0u);
  std::size_t kept = 0;
  for (const Element* j : urdf->all("joint")) {
    const std::string child = j->child("child")->at("link");
    if (find_named(*urdf, "link", child)->child("inertial") == nullptr) continue;  // the cut's mount: the frame
    const Element* sj = find_named(*model, "joint", j->at("name"));
    ASSERT_NE(sj, nullptr) << "joint " << j->at("name") << " lost";
    ++kept;
    const std::string type = j->at("type") == "continuous" ? "revolute" : j->at("type");  // SDF has no continuous
    EXPECT_EQ(sj->at("type"), type) << j->at("name");
    EXPECT_EQ(sj->child("parent")->text, j->child("parent")->at("link"));
    EXPECT_EQ(sj->child("child")->text, child);
  }
  EXPECT_EQ(model->all("joint").size(), kept);
  const std::string check = run(std::string(kIgn) + " sdf -k '" + file.string() + "' 2>&1");
  EXPECT_THAT(check, HasSubstr("Valid."));
}

TEST(Urdf, SdformatKeepsEveryLinkAndJoint) {
  if (!fs::exists(kIgn)) GTEST_SKIP() << "ign not installed (Debian packages ignition-tools, libsdformat-dev): not run";
  const Design d = paper();
  TempDir dir;
  for (const bool world : {false, true}) {
    for (const Station& s : d.stations) {
      UrdfOptions options;
      options.world_link = world;
      const fs::path file = dir.path / ((world ? "world_" : "") + urdf_file_name(d, s));
      std::ofstream(file) << render_urdf(d, s, options);
      expect_sdformat_keeps(file);
      std::string raw;
      const auto sdf = sdf_of(file, raw);
      ASSERT_NE(sdf, nullptr);
      // With `world`: the base fixed to it (SDFormat's joint to the world); without: the base is the root.
      const Element* fixed = find_named(*sdf->child("model"), "joint", s.name + "_base_to_world");
      EXPECT_EQ(fixed != nullptr, world);
      if (fixed != nullptr) EXPECT_EQ(fixed->child("parent")->text, "world");
    }
  }
}

TEST(Urdf, InitialPoseClosesEveryLoopInsideTheLimits) {
  // The elbows of initial_pose(), put through the two legs by hand, meet at the target centre.
  const Design d = paper();
  for (const Station& s : d.stations) {
    const auto pose = initial_pose(d, s);
    ASSERT_EQ(pose.size(), 4 * s.mechanisms().size());
    std::map<std::string, double> q(pose.begin(), pose.end());
    for (const Mechanism* m : s.mechanisms()) {
      const std::string p = s.name + "_" + m->name + "_";
      const double t1 = q.at(p + "theta1"), t2 = q.at(p + "theta2"), e1 = q.at(p + "elbow1"), e2 = q.at(p + "elbow2");
      const double x1 = m->O1.x() + m->L[0] * std::cos(t1) + m->L[2] * std::cos(t1 + e1);
      const double y1 = m->O1.y() + m->L[0] * std::sin(t1) + m->L[2] * std::sin(t1 + e1);
      const double x2 = m->O2.x() + m->L[1] * std::cos(t2) + m->L[3] * std::cos(t2 + e2);
      const double y2 = m->O2.y() + m->L[1] * std::sin(t2) + m->L[3] * std::sin(t2 + e2);
      EXPECT_NEAR(x1, s.target.center.x(), 1e-9);
      EXPECT_NEAR(y1, s.target.center.y(), 1e-9);
      EXPECT_NEAR(x2, s.target.center.x(), 1e-9);
      EXPECT_NEAR(y2, s.target.center.y(), 1e-9);
      for (const UsableRange& r : usable_ranges(d, s, *m)) EXPECT_GT(range_margin(r, q.at(r.joint)), 0.0) << r.joint;
    }
  }
}

// --- The ROS 2 description package -------------------------------------------------------------

/// A parts report of box STL files for the index station (as FromStlRenders... above).
Json box_parts(const fs::path& parts_dir) {
  fs::create_directories(parts_dir / "index");
  write_box(parts_dir / "index/link.stl", 0.5, -2.0, 0.0, 8.0, 4.0, 2.0);
  write_box(parts_dir / "index/tip.stl", -1.0, -1.0, 0.0, 2.0, 2.0, 1.0);
  write_box(parts_dir / "index/base.stl", -5.0, -5.0, -3.0, 25.0, 40.0, 3.0);
  Json parts = {{"parts", Json::array()}};
  parts["parts"].push_back({{"station", "index"}, {"uses", {"lower/L1", "lower/L2", "lower/L3", "lower/L4", "upper/L1",
                                                             "upper/L2", "upper/L3", "upper/L4"}},
                            {"stl", "index/link.stl"}});
  parts["parts"].push_back({{"station", "index"}, {"uses", {"lower/tactor", "upper/tactor"}}, {"stl", "index/tip.stl"}});
  parts["parts"].push_back({{"station", "index"}, {"uses", {"base"}}, {"stl", "index/base.stl"}});
  return parts;
}

TEST(Urdf, Ros2PackageParsesAndItsUrdfPassesCheckUrdfAndSdformat) {
  const Design d = paper();
  TempDir dir;
  const Json parts = box_parts(dir.path / "parts");
  ExportOptions options;
  options.stations = {"index"};
  options.ros2_package = true;
  options.ros2_package_subdir = "iros2022_description";
  options.urdf_options.parts = &parts;
  options.urdf_options.parts_dir = dir.path / "parts";
  const ExportResult r = export_controller(d, {}, dir.path / "out", options);
  ASSERT_TRUE(r.gate.passed());
  const fs::path pkg = dir.path / "out" / "iros2022_description";
  EXPECT_EQ(ros2_package_name(d), "iros2022_description");
  for (const char* f : {"package.xml", "CMakeLists.txt", "README.md", "urdf/iros2022_index.urdf", "meshes/index/link.stl",
                        "meshes/index/base.stl", "config/iros2022_controller_index.yaml", "config/ros2_controllers.yaml",
                        "launch/display.launch.py"}) {
    EXPECT_TRUE(fs::is_regular_file(pkg / f)) << f;
  }
  // CMakeLists installs exactly the folders the package has.
  const std::string cmake = slurp(pkg / "CMakeLists.txt");
  EXPECT_THAT(cmake, HasSubstr("install(DIRECTORY urdf meshes config launch DESTINATION share/${PROJECT_NAME})"));
  EXPECT_THAT(cmake, HasSubstr("find_package(ament_cmake REQUIRED)"));
  // The parameters file is the one `fivebar export` writes.
  EXPECT_EQ(slurp(pkg / "config/iros2022_controller_index.yaml"), render_ros2_yaml(r.parameters));

  // package.xml through catkin_pkg, ROS's own manifest reader (format 3, ament_cmake, validated).
  std::vector<std::string> missing;  // tools not installed: their checks are skipped, and the test says so
  const std::string probe = run("/usr/bin/python3 -c 'import catkin_pkg' 2>&1");
  if (probe.find("[exit 0]") == std::string::npos) {
    missing.push_back("python3-catkin-pkg");
  } else {
    const std::string out = run("/usr/bin/python3 -c \"from catkin_pkg.package import parse_package; p = parse_package('" +
                                pkg.string() + "'); p.validate(); print(p.name, p.package_format, "
                                "[d.name for d in p.buildtool_depends], p.get_build_type())\" 2>&1");
    EXPECT_THAT(out, HasSubstr("iros2022_description 3 ['ament_cmake'] ament_cmake"));
    EXPECT_THAT(out, HasSubstr("[exit 0]"));
  }
  // The launch file is Python the interpreter compiles.
  EXPECT_THAT(run("/usr/bin/python3 -m py_compile '" + (pkg / "launch/display.launch.py").string() + "' 2>&1"),
              HasSubstr("[exit 0]"));
  const std::string launch = slurp(pkg / "launch/display.launch.py");
  for (const auto& [joint, angle] : initial_pose(d, *d.station("index"))) {
    EXPECT_THAT(launch, HasSubstr("'" + joint + "': " + format_double(angle) + ","));
  }

  // The URDF names its meshes package://iros2022_description/meshes/...; resolved into the folder,
  // every one exists, check_urdf reads it and SDFormat keeps it.
  std::string urdf = slurp(pkg / "urdf/iros2022_index.urdf");
  const std::string scheme = "package://iros2022_description/";
  EXPECT_THAT(urdf, HasSubstr("filename=\"package://iros2022_description/meshes/index/link.stl\""));
  EXPECT_EQ(urdf.find("../parts"), std::string::npos);
  std::size_t resolved = 0;
  for (std::size_t at; (at = urdf.find(scheme)) != std::string::npos; ++resolved) {
    urdf.replace(at, scheme.size(), pkg.string() + "/");
    const std::size_t end = urdf.find('"', at);
    EXPECT_TRUE(fs::is_regular_file(urdf.substr(at, end - at))) << urdf.substr(at, end - at);
  }
  EXPECT_EQ(resolved, 1u + 2 * 5);  // the base, per mechanism four links and the tip
  const fs::path local = dir.path / "resolved.urdf";
  std::ofstream(local) << urdf;
  if (fs::exists(kCheckUrdf)) {
    const std::string out = run(std::string(kCheckUrdf) + " '" + local.string() + "' 2>&1");
    EXPECT_THAT(out, HasSubstr("root Link: world has 1 child(ren)"));
    EXPECT_THAT(out, HasSubstr("[exit 0]"));
  } else {
    missing.push_back("liburdfdom-tools");
  }
  if (fs::exists(kIgn)) {
    expect_sdformat_keeps(local);
  } else {
    missing.push_back("ignition-tools");
  }
  if (!missing.empty()) GTEST_SKIP() << "not installed, their checks not run: " << ::testing::PrintToString(missing);
}

}  // namespace
}  // namespace fivebar
