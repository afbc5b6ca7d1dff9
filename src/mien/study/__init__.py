"""Perception studies (Broekens et al., Mascaró et al.): design files, stimuli, the web runner, storage, export
and analysis.

Modules: :mod:`~mien.study.design` (the design TOML -> frozen dataclasses), :mod:`~mien.study.stimuli`
(render or take the videos, write ``manifest.json``), :mod:`~mien.study.protocol` (questions, label and
block orders per participant), :mod:`~mien.study.storage` (SQLite / PostgreSQL, one committed transaction
per answer), :mod:`~mien.study.runner` (the FastAPI web experiment), :mod:`~mien.study.export` (the long
CSV), and the analysis modules. Importing this package needs only the standard library; FastAPI,
SQLAlchemy, pandas and the renderer are imported when used (``pip install 'mien[study]'``).
"""
