#pragma once
/// Printable parts (README `parts`): for every station, the distinct parts of its linkages
/// (proximal links with a motor D-bore, distal links, the tactor post and tip) and its base, as
/// small OpenSCAD files that `use` the hand-written library scad/fivebar.scad with the design's
/// numbers; binary STL renders by `openscad --hardwarnings` (two jobs in parallel, skipping parts
/// whose inputs did not change, and rendering once parts whose sources are the same: the others
/// copy that STL); mesh checks (closed, no self-intersection, outward oriented,
/// positive volume, one shell) and design-intent checks measured on the mesh (pin-centre distance
/// equals the link length, hole diameters equal pin + 2 * clearance); a bill of materials.
///
/// Part frames (as in scad/fivebar.scad): a link's first joint axis is the z axis and its second
/// passes through (length, 0); the tactor tip's axis is the z axis; the station base is in the
/// station frame with the plate's top face at z = 0. Lengths in mm throughout.

#include <Eigen/Core>

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "fivebar/design.hpp"
#include "fivebar/error.hpp"
#include "fivebar/sections/geometry.hpp"
#include "fivebar/sections/print.hpp"
#include "fivebar/json.hpp"

namespace fivebar {

/// An external tool the request needs is not installed (openscad). Not bad input (exit 2) and
/// not an internal error: the CLI reports it and exits 1.
class ToolError : public std::runtime_error {
 public:
  explicit ToolError(const std::string& message, Remedy remedy = Remedy::none)
      : std::runtime_error(message), remedy_(remedy) {}
  /// What the caller can do about it (fivebar/error.hpp).
  Remedy remedy() const noexcept { return remedy_; }

 private:
  Remedy remedy_;
};

// --- Meshes -------------------------------------------------------------------------------------

/// An indexed triangle mesh; vertices that are bit-identical in the file are merged.
struct TriangleMesh {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<std::array<std::uint32_t, 3>> triangles;
  Eigen::Vector3d bbox_min() const;
  Eigen::Vector3d bbox_max() const;
};

/// Largest STL read_stl() reads (a part's render is megabytes).
inline constexpr std::uintmax_t kMaxStlBytes = std::uintmax_t{256} << 20;
/// Reads a binary STL (80-byte header, count, 50-byte records). Throws IoError when the file cannot
/// be read, InputError when it is not a well-formed binary STL (ASCII STL, truncated, bad count) or
/// is larger than kMaxStlBytes (checked while reading).
TriangleMesh read_stl(const std::filesystem::path& path);

/// Topological and geometric checks of a printed part (CGAL Polygon_mesh_processing).
struct MeshCheck {
  std::size_t vertices = 0;
  std::size_t triangles = 0;
  bool manifold = false;        ///< the triangles form an oriented 2-manifold (each edge in <= 2 faces)
  bool closed = false;          ///< no border edge (watertight)
  bool self_intersects = true;  ///< some pair of faces intersects (or a face is degenerate)
  bool outward = false;         ///< normals point out of the solid
  double volume_mm3 = 0.0;      ///< enclosed volume (signed by orientation; 0 unless closed)
  std::size_t components = 0;   ///< connected shells
  Eigen::Vector3d bbox_min_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d bbox_max_mm = Eigen::Vector3d::Zero();
  std::vector<std::string> problems;  ///< one line per failed check; empty = printable
  bool passed() const { return problems.empty(); }
};

/// Runs every check; `expected_components` shells are intended (1 for every fivebar part).
/// Checks that need a closed manifold are skipped (and reported failed) when it is not one.
MeshCheck check_mesh(const TriangleMesh& mesh, std::size_t expected_components = 1);

/// One hole (or peg) a part must have, for the design-intent check.
struct HoleSpec {
  std::string label;       ///< "shaft", "elbow", "tactor", "peg", "lower O1", ...
  Vec2 center_mm{0, 0};    ///< nominal axis in the part frame
  double diameter_mm = 0;  ///< narrowest width of a hole (pin + 2 clearance), widest of a peg
  bool peg = false;
  double z_min_mm = -1e9;  ///< only wall vertices with z in [z_min, z_max] belong to it
  double z_max_mm = 1e9;
};

/// A vertical cylindrical wall (hole or peg) measured on a mesh.
struct CircleFit {
  bool found = false;               ///< enough wall vertices near the nominal axis to fit
  Vec2 center_mm{0.0, 0.0};         ///< fitted axis (x, y)
  double vertex_radius_mm = 0.0;    ///< radius of the circle through the wall's vertices
  /// Narrowest width across a polygonal hole (2 x the distance from the axis to the nearest wall
  /// facet: what a pin sees), or for a peg its widest (2 x vertex radius).
  double diameter_mm = 0.0;
  std::size_t points = 0;           ///< distinct (x, y) wall vertices used
  double rms_mm = 0.0;              ///< rms distance of those vertices from the fitted circle
};

/// Measures the wall of `hole` on the mesh. Wall vertices are those within the hole's z range
/// whose distance from the nominal axis lies in [0.9 r, 1.1 r / cos(22.5 deg)] (r = half the
/// nominal diameter; the widest polygon a hole of $fn >= 8 can be); an algebraic circle fit
/// (Kasa) through their distinct (x, y) is repeated without the vertex furthest off the circle
/// until all lie on it (within tol::kCircleFitRejectRel of r): the corners where a D-bore's flat
/// cuts its arc drop out. The fit finds the axis of the circle the wall vertices really lie on:
/// a hole displaced by up to ~0.1 r is measured at its real place, one displaced further is not
/// found (found = false). Needs at least 6 distinct wall vertices.
CircleFit fit_circle_wall(const TriangleMesh& mesh, const HoleSpec& hole);

// --- Mass properties ------------------------------------------------------------------------

/// Mass properties of a homogeneous solid bounded by a closed, outward-oriented triangle mesh, in
/// the mesh's frame (mm). Volume integrals turned into surface integrals by the divergence theorem
/// and summed exactly per triangle: D. Eberly, "Polyhedral Mass Properties (Revisited)", Geometric
/// Tools (2002, rev. 2009), after B. Mirtich, "Fast and Accurate Computation of Polyhedral Mass
/// Properties", J. Graphics Tools 1(2), 1996. Coordinates are taken relative to the bounding-box
/// centre first, so that a part far from its origin loses no digits.
struct MassProperties {
  double volume_mm3 = 0.0;                                 ///< signed: negative when inward oriented
  double mass_kg = 0.0;                                    ///< density x volume
  Eigen::Vector3d com_mm = Eigen::Vector3d::Zero();        ///< centre of mass
  /// Inertia tensor about the centre of mass, axes of the mesh frame (kg mm^2):
  /// I = integral rho (|r|^2 1 - r r^T) dV with r from the centre of mass.
  Eigen::Matrix3d inertia_kg_mm2 = Eigen::Matrix3d::Zero();
};

/// Mass properties of `mesh` at `density_g_cm3` (g/cm^3 = 1e-6 kg/mm^3). The mesh must be closed
/// and consistently oriented (check_mesh()); InputError when its volume is not positive.
MassProperties mass_properties(const TriangleMesh& mesh, double density_g_cm3);

/// The same body moved rigidly: rotated by `R` then translated by `t` (mm); the inertia about the
/// centre of mass turns as R I R^T.
MassProperties transformed(const MassProperties& m, const Eigen::Matrix3d& R, const Eigen::Vector3d& t);

/// Inertia tensor of `m` about the point `p` (mm), by the parallel-axis theorem:
/// I_p = I_com + mass (|d|^2 1 - d d^T), d = com - p (kg mm^2).
Eigen::Matrix3d inertia_about(const MassProperties& m, const Eigen::Vector3d& p);

// --- Parts --------------------------------------------------------------------------------------

enum class PartKind { proximal_link, distal_link, tactor_tip, station_base };
std::string_view to_string(PartKind kind);

/// Sizes the design file does not give (motors, finger rest, gripper mount, hub, tip), mm. The
/// defaults describe the paper's device in spirit: small round gearmotors face-mounted under the
/// base, a 16 mm finger, an omega.7 gripper clamp on two M3 screws.
struct PartsHardware {
  double hub_height = 2.5;          ///< proximal hub below the plate (shaft grip = hub + plate)
  double tip_flange_height = 1.0;   ///< tactor tip: cylinder above the post
  double tip_dome_height = 1.0;     ///< tactor tip: dome above the flange
  double base_plate_thickness = 3.0;
  double base_margin = 2.0;         ///< plate beyond each motor's radius
  double motor_diameter = 10.0;     ///< round gearbox; neighbouring base joints must be this far apart
  double motor_bushing_diameter = 4.0;
  double motor_screw_diameter = 1.8;
  double motor_screw_spacing = 8.0;
  double finger_diameter = 16.0;
  double rest_length = 10.0;        ///< finger rest along x
  double rest_wall = 2.0;
  double mount_hole_diameter = 3.2;
  double mount_spacing = 16.0;
  double mount_pad = 4.0;
  /// Throws ValidationError naming the field.
  void validate() const;
};

/// One distinct part of a station: identical pieces (the four proximal links of a symmetric
/// station) are one part with a count.
struct PartSpec {
  std::string station;
  std::string name;                     ///< file stem, e.g. "proximal_link_9mm"
  PartKind kind = PartKind::proximal_link;
  std::vector<std::string> uses;        ///< pieces it makes: "lower/L1", "upper/L2", "lower/tactor", "base"
  std::string mechanisms;               ///< "lower", "upper", "lower+upper" or "-" (the base)
  int count = 1;                        ///< pieces to print
  double length_mm = 0.0;               ///< link centre distance (links), 0 otherwise
  std::vector<HoleSpec> holes;          ///< measured on the mesh after rendering
  std::optional<double> height_mm;      ///< expected z extent of the mesh, when the design fixes it
  std::string scad;                     ///< text of the top-level .scad file
  /// `station/name`
  std::string label() const { return station + "/" + name; }
};

struct PartsOptions {
  /// The parts folder itself (the CLI and the scene use `<out_root>/<design name>/parts`).
  std::filesystem::path out_dir = "outputs/parts";
  std::optional<std::string> station;   ///< only this station
  bool render = true;                   ///< false: write the .scad files (and a count-only BOM)
  int jobs = 2;                         ///< openscad processes at once
  /// Library folder holding fivebar.scad; empty = default_scad_dir().
  std::filesystem::path scad_dir;
  /// openscad executable; empty = FIVEBAR_OPENSCAD from the environment, else `openscad` on PATH.
  std::string openscad;
  std::optional<int> fn;                ///< overrides print.fn (drafts, tests)
  PartsHardware hardware;
  /// Progress lines ("[2/5] index/proximal_link_9mm rendered in 1.2 s"); may be empty.
  std::function<void(std::string_view)> progress;
};

/// The library folder: FIVEBAR_SCAD_DIR from the environment, else `share/fivebar/scad` found
/// above the binary (fivebar/share.hpp find_share_path), else `scad` in the working directory.
std::filesystem::path default_scad_dir();
/// Full path of the openscad executable `options.openscad` names (see there), or std::nullopt.
std::optional<std::filesystem::path> find_openscad(const std::string& name = {});

/// The parts of every station (or options.station) with their .scad text. Validates first and
/// throws InputError (nothing written) for a design without `geometry:`, an unknown station, or
/// numbers that cannot be printed: a link too short for its pin bosses (key
/// "stations.S.mechanisms.M.links[i]"), walls under print.min_wall, a tactor post of no height,
/// motors that do not fit side by side.
std::vector<PartSpec> plan_parts(const Design& design, const PartsOptions& options = {});

enum class RenderState { not_requested, rendered, up_to_date, failed };
std::string_view to_string(RenderState state);

/// What happened to one part.
struct PartResult {
  PartSpec spec;
  std::filesystem::path scad_file;   ///< relative to out_dir
  std::filesystem::path stl_file;    ///< relative to out_dir (may not exist)
  RenderState render = RenderState::not_requested;
  double render_seconds = 0.0;       ///< openscad's wall time (0 when up to date)
  std::string render_error;          ///< openscad's warnings and errors when it failed
  /// The part (PartSpec::label()) whose render this one copied, its source being the same; empty
  /// when openscad rendered this one (or it was up to date).
  std::string copied_from;
  std::optional<MeshCheck> mesh;     ///< after a render or when up to date
  std::vector<CircleFit> holes;      ///< one per spec.holes
  std::optional<double> centre_distance_mm;  ///< links: measured distance of the two joint axes
  std::vector<std::string> problems; ///< render, mesh and intent failures
  bool passed() const { return problems.empty(); }
};

struct PartsReport {
  std::filesystem::path out_dir;
  std::optional<std::filesystem::path> openscad;  ///< the executable used (when rendering)
  bool rendered = false;                          ///< renders were requested
  std::vector<PartResult> parts;
  std::filesystem::path bom_csv;                  ///< relative to out_dir
  std::vector<std::filesystem::path> files;       ///< every file written or kept, relative to out_dir
  double wall_seconds = 0.0;                      ///< whole build
  std::size_t count(RenderState state) const;
  /// Every part rendered (or up to date) and passed its checks; true for --no-render.
  bool passed() const;
  double resin_ml() const;                        ///< total over the BOM
};

/// Writes the .scad files and the library copy under options.out_dir, renders (unless
/// !options.render), checks, and writes bom.csv; every file atomically. Throws InputError (via
/// plan_parts, before writing anything), ToolError when rendering is asked for and openscad is
/// not installed (before writing anything), IoError when the output cannot be written.
PartsReport build_parts(const Design& design, const PartsOptions& options = {});

/// The report as JSON (units at the edges).
Json to_json(const PartsReport& report);

/// The BOM text: part,station,mechanism,links,count,volume_mm3,resin_ml,bbox_mm,stl; resin_ml
/// is count x volume / 1000 (no supports); bbox "XxYxZ" in mm. Empty measured fields when not
/// rendered.
std::string bom_csv(const PartsReport& report);

}  // namespace fivebar
