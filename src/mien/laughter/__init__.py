"""Laughter and smiles (Mascaró et al. 2021): taxonomy, facial parameters, controllers, DTW, library, generator."""
