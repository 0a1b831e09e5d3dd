//! voxel-render
