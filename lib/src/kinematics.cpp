// Kinematics: being written.
