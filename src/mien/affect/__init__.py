"""Emotions (Broekens et al.): events, envelopes, mood, PAD, blends and expression bases."""
