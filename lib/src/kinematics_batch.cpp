// Batch kinematics: being written.
