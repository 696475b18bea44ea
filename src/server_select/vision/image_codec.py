"""sensor_msgs/Image <-> numpy without cv_bridge (no rospy).

Supported encodings: ``bgr8``, ``rgb8``, ``mono8``, with any ``step`` (row padding).
Everything else, and sizes that do not add up, raise :class:`ImageError` with the reason.
"""

import numpy as np

CHANNELS = {'bgr8': 3, 'rgb8': 3, 'mono8': 1}


class ImageError(ValueError):
    """An image message that cannot be converted; the message says why."""


def to_array(encoding, height, width, step, data):
    """The image as a numpy array: BGR ``(h, w, 3)`` for colour, ``(h, w)`` for mono8.

    ``data`` is the message's ``bytes`` (or any buffer). The result does not share memory
    with ``data`` when padding or channel order had to be undone.
    """
    if encoding not in CHANNELS:
        raise ImageError('unsupported encoding %r (supported: %s)'
                         % (encoding, ', '.join(sorted(CHANNELS))))
    channels = CHANNELS[encoding]
    if height <= 0 or width <= 0:
        raise ImageError('empty image (%dx%d)' % (width, height))
    row = width * channels
    if step < row:
        raise ImageError('step %d is smaller than width x channels = %d' % (step, row))
    buffer = np.frombuffer(data, dtype=np.uint8)
    if buffer.size != step * height:
        raise ImageError('data has %d bytes, expected step x height = %d x %d = %d'
                         % (buffer.size, step, height, step * height))
    pixels = buffer.reshape(height, step)[:, :row]
    if channels == 1:
        return pixels.reshape(height, width)
    pixels = pixels.reshape(height, width, 3)
    return pixels[:, :, ::-1] if encoding == 'rgb8' else pixels


def from_array(array, encoding='bgr8'):
    """``(encoding, height, width, step, data)`` for a BGR or mono numpy array.

    ``rgb8`` converts BGR input to RGB; ``mono8`` needs a 2-D array.
    """
    array = np.asarray(array)
    if array.dtype != np.uint8:
        raise ImageError('expected uint8 pixels, got %s' % array.dtype)
    if encoding == 'mono8':
        if array.ndim != 2:
            raise ImageError('mono8 needs a 2-D array, got shape %s' % (array.shape,))
    elif encoding in ('bgr8', 'rgb8'):
        if array.ndim != 3 or array.shape[2] != 3:
            raise ImageError('%s needs an (h, w, 3) array, got shape %s' % (encoding, array.shape))
        if encoding == 'rgb8':
            array = array[:, :, ::-1]
    else:
        raise ImageError('unsupported encoding %r' % encoding)
    array = np.ascontiguousarray(array)
    height, width = array.shape[:2]
    return encoding, height, width, array.strides[0], array.tobytes()


def to_gray(array):
    """Grey-scale view of a BGR or mono array (as detectors want it)."""
    if array.ndim == 2:
        return array
    import cv2
    return cv2.cvtColor(array, cv2.COLOR_BGR2GRAY)
