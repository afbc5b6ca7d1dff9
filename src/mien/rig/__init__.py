"""Rigs: meshes with morph targets, AU->blendshape mapping, heads, the feature-point rig and deformation."""
