"""Captures of the physical camera: reading them, checking them, their grey levels."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

from .._io import max_image_pixels
from ..camera import FisheyeCamera
from ..errors import InputFileError, RvmsimError

__all__ = ["load_capture", "check_capture_size", "grey", "capture_header_size"]


def load_capture(path: str | Path, camera: FisheyeCamera | None = None) -> np.ndarray:
    """Read a capture as (H, W, 3) uint8 RGB.

    Grey images are expanded to three channels, an alpha channel is dropped, 16-bit images
    are scaled to 8 bits.

    Parameters
    ----------
    path : path
        PNG, JPEG, TIFF or anything else OpenCV decodes.
    camera : FisheyeCamera, optional
        When given, the capture must be ``camera.width`` × ``camera.height`` px.

    Raises
    ------
    RvmsimError
        One line naming the file: missing, unreadable, empty or blank, over the image pixel
        limit (``RVMSIM_MAX_IMAGE_PIXELS``), or (with ``camera``) a size other than the
        camera's; the size is checked from the file's header, before the pixels are decoded.
    """
    path = Path(path)
    w, h = capture_header_size(path)
    if camera is not None and (w, h) != (camera.width, camera.height):
        raise _size_error(path, w, h, camera)
    limit = max_image_pixels()
    if w * h > limit:
        raise InputFileError(str(path), "", f"capture is {w}×{h} = {w * h} px, over the limit "
                             f"of {limit} px (raise it with RVMSIM_MAX_IMAGE_PIXELS)")
    img = _to_rgb8(_decode(path), path)
    h, w = img.shape[:2]
    if camera is not None and (w, h) != (camera.width, camera.height):
        raise _size_error(path, w, h, camera)
    if float(img.std()) < 1.0:
        raise RvmsimError(f"{path}: capture is blank (every pixel ≈ {int(img.mean())})")
    return img


def _size_error(path: Path, w: int, h: int, camera: FisheyeCamera) -> InputFileError:
    return InputFileError(str(path), "", f"capture is {w}×{h} px but the scene's "
                          f"camera.image_size is {camera.width}×{camera.height} px")


def capture_header_size(path: Path) -> tuple[int, int]:
    """(width, height) in px of the image file at ``path``, from its header alone (PIL's
    lazy open: no pixel is decoded).

    Raises
    ------
    InputFileError
        One line naming the file: missing, empty, unreadable or not an image, or a header
        so large that PIL refuses it as a decompression bomb.
    """
    from PIL import Image, UnidentifiedImageError

    if not path.is_file():
        raise InputFileError(str(path), "", "capture not found")
    try:
        if path.stat().st_size == 0:
            raise InputFileError(str(path), "", "capture is an empty file")
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", Image.DecompressionBombWarning)  # our own limit
            with Image.open(path) as im:
                return int(im.width), int(im.height)
    except Image.DecompressionBombError:
        raise InputFileError(str(path), "", "capture's header gives more than "
                             f"{2 * (Image.MAX_IMAGE_PIXELS or 0)} px, over the limit of "
                             f"{max_image_pixels()} px") from None
    except UnidentifiedImageError:
        raise InputFileError(str(path), "", "cannot read capture (not a PNG, JPEG, TIFF or "
                             "other image file)") from None
    except OSError as err:
        raise InputFileError(str(path), "", f"cannot read capture ({err.strerror or err})"
                             ) from None


def _decode(path: Path) -> np.ndarray:
    """The file's pixels as OpenCV decodes them (any depth, BGR(A) or grey)."""
    import cv2

    if not path.is_file():
        raise RvmsimError(f"{path}: capture not found")
    try:
        data = np.fromfile(path, dtype=np.uint8)
    except OSError as err:
        raise RvmsimError(f"{path}: cannot read capture ({err.strerror or err})") from None
    if data.size == 0:
        raise RvmsimError(f"{path}: capture is an empty file")
    try:
        img = cv2.imdecode(data, cv2.IMREAD_UNCHANGED)
    except cv2.error as err:
        first = (str(err).strip().splitlines() or ["?"])[-1][:160]
        raise RvmsimError(f"{path}: cannot read capture ({first})") from None
    if img is None or img.size == 0:
        raise RvmsimError(f"{path}: cannot read capture (not an image OpenCV can decode)")
    return np.asarray(img)


def _to_rgb8(img: np.ndarray, path: Path) -> np.ndarray:
    """8-bit RGB from OpenCV's decoded 8/16-bit grey, BGR or BGRA."""
    import cv2

    if img.dtype == np.uint16:
        img = (img.astype(np.uint16) >> 8).astype(np.uint8)
    elif img.dtype != np.uint8:
        raise RvmsimError(f"{path}: capture has {img.dtype} pixels (need 8- or 16-bit)")
    if img.ndim == 2:
        return np.asarray(cv2.cvtColor(img, cv2.COLOR_GRAY2RGB))
    if img.shape[2] == 4:
        return np.asarray(cv2.cvtColor(img, cv2.COLOR_BGRA2RGB))
    return np.asarray(cv2.cvtColor(img, cv2.COLOR_BGR2RGB))


def check_capture_size(capture: np.ndarray, camera: FisheyeCamera, capture_name: str) -> None:
    """Refuse a capture that is not an (H, W, 3) image of ``camera``'s size.

    Raises
    ------
    RvmsimError
        One line naming ``capture_name`` and both sizes (px).
    """
    if capture.shape[:2] != (camera.height, camera.width) or capture.ndim != 3:
        raise RvmsimError(f"{capture_name}: capture is {capture.shape[1]}×{capture.shape[0]} px "
                          f"but the scene's camera is {camera.width}×{camera.height} px")


def grey(rgb: np.ndarray) -> np.ndarray:
    """Grey levels (0..255, float32, (H, W)) of an (H, W, 3) uint8 RGB image."""
    import cv2

    return np.asarray(cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY), dtype=np.float32)
