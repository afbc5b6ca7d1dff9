"""Validation: detectors over rendered and real faces, AU estimates, recognition, activation maps, reports.

The one interface is :class:`~mien.validate.detector.Detector` (an RGB frame in, a
:class:`~mien.validate.detector.Detection` out); everything else (rig fidelity, emotion recognition, the
OpenFACS comparison, the HTML report) works through it. Heavy dependencies (mediapipe, ai-edge-litert,
scipy) load only when a detector or solver is built.
"""
