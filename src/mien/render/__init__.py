"""Offline rendering: cameras (with the Broekens study presets), a headless moderngl/EGL renderer, MP4 and
PNG writing, contact sheets, and whole clips from a rig and its morph-target weights.

Importing this package needs only numpy; moderngl, imageio-ffmpeg, Pillow and PyAV (``pip install
'mien[render]'``) are imported when used.
"""

from mien.render.camera import CAMERA_PRESETS, STUDY_FOV_DEG, VIEWS, Camera, View, camera_from_options
from mien.render.clip_render import render_clip, render_still
from mien.render.contact_sheet import contact_sheet
from mien.render.offscreen import EGLUnavailableError, OffscreenRenderer, vertex_normals
from mien.render.video import EncodedVideo, read_video_info, write_mp4, write_png

__all__ = [
    "CAMERA_PRESETS",
    "STUDY_FOV_DEG",
    "VIEWS",
    "Camera",
    "EGLUnavailableError",
    "EncodedVideo",
    "OffscreenRenderer",
    "View",
    "camera_from_options",
    "contact_sheet",
    "read_video_info",
    "render_clip",
    "render_still",
    "vertex_normals",
    "write_mp4",
    "write_png",
]
