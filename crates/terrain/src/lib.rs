//! The terrain engine: a height-mapped island standing in a translucent, reflecting sea under a
//! sky box, drawn with wgpu. World convention: **y-up**, the water is the plane y = 0.
