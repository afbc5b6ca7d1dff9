"""FACS: the action-unit catalogue, face frames and clips, dynamics, prototypes and idle behaviour."""
