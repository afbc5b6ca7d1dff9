"""Validation: detectors over rendered and real faces, AU estimates, recognition, activation maps, reports.

The one interface is :class:`~mien.validate.detector.Detector` (an RGB frame in, a
:class:`~mien.validate.detector.Detection` out); everything else works through it. The modules, by job:

* statistics: :mod:`~mien.validate.statistics` (Pearson's r, slopes, Wilson intervals),
  :mod:`~mien.validate.activation` (AU activation maps and their 2D correlation);
* what is judged: :mod:`~mien.validate.expressions` (the study's expressions, the classifier label of each, the
  people's quality), views from :data:`mien.render.camera.VIEWS`;
* evidence: :mod:`~mien.validate.detector`, :mod:`~mien.validate.face_detector`,
  :mod:`~mien.validate.emotion_classifier`, :mod:`~mien.validate.landmark_aus`,
  :mod:`~mien.validate.facs_reading`, :mod:`~mien.validate.human_evidence`, :mod:`~mien.validate.judge` (what a
  verdict is: the classifier's probabilities averaged over twelve crops);
* results: :mod:`~mien.validate.scores` (recognition), :mod:`~mien.validate.targets` (the scorecard, per kind of head);
* runs that render and judge: :mod:`~mien.validate.stimuli`, :mod:`~mien.validate.recognition`,
  :mod:`~mien.validate.rig_fidelity`, :mod:`~mien.validate.compare`;
* output: :mod:`~mien.validate.figures`, :mod:`~mien.validate.report`, taking a
  :class:`~mien.validate.options.ValidateOptions` (the CLI builds it; the library never reads argparse).

Heavy dependencies (mediapipe, ai-edge-litert, moderngl, matplotlib, scipy) load only when a detector, renderer,
solver or figure is built, through :func:`mien.extras.require`.
"""
