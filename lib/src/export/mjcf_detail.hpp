#pragma once
// Private to lib: the XML writing the MJCF (mjcf.cpp) and the MuJoCo bundle's scene (mujoco_bundle.cpp)
// share: numbers in their shortest form, millimetres written as metres, quoted attributes, comments.

#include <sstream>
#include <string>

namespace fivebar::detail {

std::string mj_num(double v);
/// `mm` in metres.
std::string mj_m(double mm);
/// `"s"` with XML escapes.
std::string mj_q(const std::string& s);
/// `"x y z"` in metres from millimetres.
std::string mj_vec(double x_mm, double y_mm, double z_mm);
/// Text for an XML comment (read literally): no "--" inside, no '-' at its end.
std::string mj_comment_text(std::string text);

struct MjWriter {
  std::ostringstream out;
  void line(int indent, const std::string& text) { out << std::string(static_cast<std::size_t>(2 * indent), ' ') << text << "\n"; }
  void comment(int indent, const std::string& text) { line(indent, "<!-- " + mj_comment_text(text) + " -->"); }
};

}  // namespace fivebar::detail
