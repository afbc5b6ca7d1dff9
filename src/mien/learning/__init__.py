"""Offline learning of laugh and smile libraries from video (Mascaró et al. 2021): takes -> controller curves,
DTW, clustering, barycentres, the learning pipeline. Runtime laughter lives in :mod:`mien.laughter`."""
