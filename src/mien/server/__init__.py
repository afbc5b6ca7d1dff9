"""Live serving: the OpenFACS UDP API, a WebSocket frame stream and an HTTP API in one asyncio process.

Modules: :mod:`~mien.server.protocol` (messages, the one parser, the binary frame format),
:mod:`~mien.server.registry` (characters), :mod:`~mien.server.scheduler` (the clock),
:mod:`~mien.server.udp`, :mod:`~mien.server.websocket`, :mod:`~mien.server.http_api` (transports),
:mod:`~mien.server.app` (wiring, :func:`~mien.server.app.serve`). FastAPI and uvicorn are imported only by
``http_api`` and ``app`` (``pip install 'mien[serve]'``).
"""
