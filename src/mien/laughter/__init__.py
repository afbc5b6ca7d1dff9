"""Laughter and smiles at run time (Mascaró et al. 2021): taxonomy, facial parameters, controllers, library,
generator. Learning libraries from video lives in :mod:`mien.learning`."""
