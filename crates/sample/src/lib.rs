//! Generator of the bundled CC0 sample pose set: poses the MakeHuman base body with
//! forward kinematics and linear blend skinning on the `cmu_mb` rig.
