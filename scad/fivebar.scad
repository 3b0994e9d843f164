// fivebar.scad: parametric printed parts of the five-bar cutaneous feedback interface
// (IROS 2022: two finger stations, each with a lower and an upper five-bar linkage; links and
// bases printed on a Formlabs Form 2 in Tough 2000 resin).
//
// Plain OpenSCAD primitives only (OpenSCAD 2021.01, no third-party library). `fivebar parts`
// writes one small top-level file per part that `use`s this file and calls one module with the
// design's numbers; the modules can also be called by hand. Every length is in millimetres.
//
// Conventions shared by every module:
// - Holes are "polyholes": the $fn-gon is circumscribed about the nominal circle, so the
//   narrowest width of a printed hole is the nominal diameter, never less (a polygon inscribed in
//   the circle would eat cos(180/$fn) of the pin clearance).
// - `clearance` is radial: a pin of diameter d goes into a hole of diameter d + 2 * clearance.
// - Link frame: the first joint axis is the z axis, the second joint axis passes through
//   (length, 0); the link plate spans z = 0 ... thickness. So the centre distance of the holes is
//   exactly `length`.
// - Station frame (station_base): x from the lower mechanism's first base joint toward its second,
//   y toward the upper base line, z up; the plate's top face is z = 0.

// ------------------------------------------------------------------------------------------------
// Helpers

// Polygon circumscribed about the circle of diameter d: its narrowest width is d.
module fb_polyhole(d) {
  circle(r = d / 2 / cos(180 / $fn));
}

// 2-D outline of a straight link: a bar of width `width` between (0,0) and (length,0) with a round
// boss of diameter `boss_d0` at the first joint and `boss_d1` at the second.
module fb_link_outline(length, width, boss_d0, boss_d1) {
  translate([0, -width / 2]) square([length, width]);
  circle(d = boss_d0);
  translate([length, 0]) circle(d = boss_d1);
}

// 2-D D-shaped bore for a D-shaft of diameter shaft_d whose flat is `flat` deep, both grown by
// the radial clearance. The flat faces +y.
module fb_d_bore(shaft_d, flat, clearance) {
  r = shaft_d / 2 + clearance;
  R = r / cos(180 / $fn);
  intersection() {
    fb_polyhole(2 * r);
    translate([-R - 1, -R - 1]) square([2 * R + 2, R + 1 + (r - flat)]);
  }
}

// ------------------------------------------------------------------------------------------------
// proximal_link: the motor-driven link L1 or L2.
// A plate `length` long (centre distance from the motor shaft to the elbow pin), a hub around a
// D-bore that takes the motor's D-shaft at (0,0) and a pin hole at (length,0). The hub reaches
// `hub_height` below the plate (toward the motor) so that the shaft grips over hub_height +
// thickness; the distal link pinned at the far end moves above the plate, clear of the hub.
//   length      centre distance shaft axis -> pin axis (the design's L1 / L2)
//   width       plate width
//   thickness   plate thickness
//   boss_d      diameter of the rounded end around the pin
//   hub_d       outer diameter of the hub around the shaft
//   hub_height  how far the hub reaches below the plate (0: no hub)
//   pin_d       nominal pin diameter; the hole is pin_d + 2 * clearance
//   shaft_d     motor shaft diameter; shaft_flat: depth of its flat
//   clearance   radial clearance of the pin hole and of the D-bore
module proximal_link(length = 9, width = 4, thickness = 2.5, boss_d = 5, hub_d = 5.5, hub_height = 2.5,
                     pin_d = 2, shaft_d = 3, shaft_flat = 0.5, clearance = 0.15) {
  difference() {
    union() {
      linear_extrude(height = thickness) fb_link_outline(length, width, hub_d, boss_d);
      if (hub_height > 0) translate([0, 0, -hub_height]) cylinder(d = hub_d, h = hub_height + thickness / 2);
    }
    translate([0, 0, -hub_height - 1])
      linear_extrude(height = hub_height + thickness + 2) fb_d_bore(shaft_d, shaft_flat, clearance);
    translate([length, 0, -1]) linear_extrude(height = thickness + 2) fb_polyhole(pin_d + 2 * clearance);
  }
}

// ------------------------------------------------------------------------------------------------
// distal_link: L3 or L4, from an elbow pin at (0,0) to the tactor pin at (length,0).
// The distal link that carries the tactor has a hollow post at the tactor end (post_height > 0):
// the pin hole runs up through it, the pin at P fills its lower part and the tactor tip's peg
// plugs into its top.
//   length       centre distance of the two pins (the design's L3 / L4)
//   width, thickness, boss_d, pin_d, clearance: as for proximal_link
//   post_height  height of the tactor post above the plate's top face (0: no post)
//   post_d       outer diameter of the post
module distal_link(length = 15, width = 4, thickness = 2.5, boss_d = 5, pin_d = 2, clearance = 0.15,
                   post_height = 0, post_d = 5) {
  top = thickness + post_height;
  difference() {
    union() {
      linear_extrude(height = thickness) fb_link_outline(length, width, boss_d, boss_d);
      if (post_height > 0) translate([length, 0, thickness / 2]) cylinder(d = post_d, h = top - thickness / 2);
    }
    translate([0, 0, -1]) linear_extrude(height = thickness + 2) fb_polyhole(pin_d + 2 * clearance);
    translate([length, 0, -1]) linear_extrude(height = top + 2) fb_polyhole(pin_d + 2 * clearance);
  }
}

// ------------------------------------------------------------------------------------------------
// tactor_tip: the part that touches the fingertip. A solid of revolution about z: a peg below
// z = 0 that plugs into the tactor post's bore, a flange resting on the post, and a flattened
// dome on top (smooth contact with the skin).
//   diameter       flange and dome diameter (the design's tactor_diameter)
//   flange_height  cylindrical part above the post
//   dome_height    height of the dome above the flange
//   peg_d          peg diameter (the pin diameter: it slides into the pin hole with clearance)
//   peg_length     length of the peg
module tactor_tip(diameter = 4, flange_height = 1, dome_height = 1, peg_d = 2, peg_length = 2) {
  r = diameter / 2;
  n = max(4, ceil($fn / 4));
  dome = [for (i = [1:n]) [r * cos(90 * i / n), flange_height + dome_height * sin(90 * i / n)]];
  rotate_extrude()
    polygon(concat([[0, -peg_length], [peg_d / 2, -peg_length], [peg_d / 2, 0], [r, 0], [r, flange_height]],
                   [for (i = [0:n - 2]) dome[i]], [[0, flange_height + dome_height]]));
}

// ------------------------------------------------------------------------------------------------
// station_base: the base of one finger station, in the station frame (top face of the plate at
// z = 0, the plate below it).
// - Motor mounts at every base joint of both mechanisms: the motors hang under the plate, face
//   mounted; a hole through the plate locates the gearbox bushing (the shaft passes through it
//   and carries the proximal link above the plate) and two screw holes either side along y hold
//   the gearbox face.
// - Finger rest: a block on the plate with a cylindrical groove along x that supports the finger
//   behind the fingertip; the groove bottom is at the height of the tactor tips. Place it outside
//   the area the links sweep.
// - Gripper mount: two screw holes along y in a tab of the plate, to bolt the station to a clamp
//   on the haptic device's gripper (Force Dimension omega.7 in the paper).
// The plate, its holes and the rest's profile are 2-D shapes extruded once each; the only 3-D
// operation is the union of the plate and the rest (OpenSCAD 2021's CGAL union is the slow step).
//   motor_positions  base joints [[x, y], ...] (station frame)
//   plate_thickness  base plate thickness
//   margin           plate material around each motor (beyond motor_d / 2)
//   motor_d          motor gearbox diameter (sets the plate outline around each base joint)
//   bushing_d        hole through the plate for the gearbox bushing and shaft
//   screw_d          motor screw holes; screw_spacing: their distance (along y)
//   rest_x0, rest_x1 x extent of the finger rest; rest_y: its centre line
//   rest_height      groove bottom above the plate's top face
//   finger_d         groove diameter; rest_wall: material either side of the groove
//   mount_x          x of the gripper screws; mount_y: centre of the pair
//   mount_spacing    distance of the two gripper screws; mount_hole_d: their hole diameter
//   mount_pad        plate material around the gripper screws
module station_base(motor_positions = [[0, 0], [12.5, 0], [0, 31], [12.5, 31]], plate_thickness = 3,
                    margin = 2, motor_d = 10, bushing_d = 4, screw_d = 1.8, screw_spacing = 8,
                    rest_x0 = -40, rest_x1 = -30, rest_y = 15.5, rest_height = 14, finger_d = 16,
                    rest_wall = 2, mount_x = 30, mount_y = 15.5, mount_spacing = 16, mount_hole_d = 3.2,
                    mount_pad = 4) {
  rest_w = finger_d + 2 * rest_wall;
  rest_top = rest_height + 0.4 * finger_d;
  union() {
    translate([0, 0, -plate_thickness]) linear_extrude(height = plate_thickness) difference() {
      hull() {
        for (p = motor_positions) translate(p) circle(d = motor_d + 2 * margin);
        translate([rest_x0, rest_y - rest_w / 2]) square([rest_x1 - rest_x0, rest_w]);
        for (s = [-1, 1]) translate([mount_x, mount_y + s * mount_spacing / 2]) circle(d = mount_hole_d + 2 * mount_pad);
      }
      for (p = motor_positions) {
        translate(p) fb_polyhole(bushing_d);
        for (s = [-1, 1]) translate([p[0], p[1] + s * screw_spacing / 2]) fb_polyhole(screw_d);
      }
      for (s = [-1, 1]) translate([mount_x, mount_y + s * mount_spacing / 2]) fb_polyhole(mount_hole_d);
    }
    // Finger rest: its yz profile extruded from rest_x0 to rest_x1, sunk half the plate into the
    // plate so that the union is one solid.
    translate([rest_x0, 0, 0]) rotate([90, 0, 90]) linear_extrude(height = rest_x1 - rest_x0) difference() {
      translate([rest_y - rest_w / 2, -plate_thickness / 2]) square([rest_w, rest_top + plate_thickness / 2]);
      translate([rest_y, rest_height + finger_d / 2]) circle(d = finger_d);
    }
  }
}
