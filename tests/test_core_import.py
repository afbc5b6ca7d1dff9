import subprocess
import sys


def test_core_import_pulls_in_numpy_only():
    code = (
        "import sys, mien; "
        "heavy = [m for m in ('matplotlib', 'moderngl', 'mediapipe', 'numba', 'cv2', 'av', 'scipy', 'dask', 'PIL') "
        "if m in sys.modules]; print(heavy)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


def test_cli_help_is_fast_to_import():
    out = subprocess.run(
        [sys.executable, "-c", "import sys, mien.cli; mien.cli.build_parser(); print('numba' in sys.modules)"],
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    assert out.strip() == "False"
