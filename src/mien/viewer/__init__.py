"""The browser viewer served by ``mien serve`` at ``/``: a three.js page showing a character's head live.

``static/`` holds the page (``index.html``, ``viewer.js``, ``viewer.css``; plain ES modules, no build step).
:mod:`mien.viewer.controls` builds the lists the page's controls show (AUs, emotions, laughter types, idle
parts, camera presets) from the package's own catalogues; :mod:`mien.viewer.vendor` finds three.js (in a
wheel, ``mien/viewer/three``, copied from npm when the wheel is built; in a checkout, ``node_modules``);
:mod:`mien.viewer.routes` mounts it all on a FastAPI app. The repository never holds three.js and nothing is
fetched from the internet.
"""
