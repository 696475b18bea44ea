"""sensor_msgs/Image and CompressedImage <-> numpy without cv_bridge (no rospy).

Raw encodings: ``bgr8``, ``rgb8``, ``mono8``, with any ``step`` (row padding); compressed:
JPEG and PNG (``format`` as image_transport's compressed plugin writes it, e.g.
``bgr8; jpeg compressed bgr8`` or plain ``jpeg``). Everything else, and sizes that do not
add up, raise :class:`ImageError` with the reason.
"""

from server_select.core.settings import MAX_IMAGE_PIXELS
from server_select.core.util.lazy import deferred
from server_select.vision.image_header import HeaderError, dimensions

np = deferred('numpy')


CHANNELS = {'bgr8': 3, 'rgb8': 3, 'mono8': 1}
MAX_PIXELS = MAX_IMAGE_PIXELS      # the largest frame taken by default


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


def encode(array, quality=80, kind='jpeg'):
    """``(format, bytes)`` of a BGR or mono array compressed as ``jpeg`` (``quality``
    0-100) or ``png``; the format string is image_transport's."""
    import cv2
    if kind not in ('jpeg', 'png'):
        raise ImageError('unsupported compression %r (jpeg or png)' % kind)
    params = [cv2.IMWRITE_JPEG_QUALITY, int(quality)] if kind == 'jpeg' else []
    ok, data = cv2.imencode('.jpg' if kind == 'jpeg' else '.png', np.asarray(array), params)
    if not ok:
        raise ImageError('cannot compress an array of shape %s' % (np.shape(array),))
    encoding = 'mono8' if np.ndim(array) == 2 else 'bgr8'
    return '%s; %s compressed %s' % (encoding, kind, encoding), data.tobytes()


def decode(fmt, data, max_pixels=MAX_PIXELS):
    """The BGR array of a compressed frame (JPEG or PNG); a frame that does not decode, or
    whose header says it has more than ``max_pixels``, raises ImageError."""
    import cv2
    if not any(k in fmt.lower() for k in ('jpeg', 'jpg', 'png')):
        raise ImageError('unsupported compressed format %r (jpeg or png)' % fmt)
    if not len(data):
        raise ImageError('empty compressed frame')
    try:        # its size from its header, before a byte of it is decoded
        width, height = dimensions(data)
    except HeaderError as error:
        raise ImageError('compressed frame (%s, %d bytes) does not decode: %s'
                         % (fmt, len(data), error))
    if width * height > max_pixels:
        raise ImageError('compressed frame of %dx%d exceeds max_image_pixels %d'
                         % (width, height, max_pixels))
    frame = cv2.imdecode(np.frombuffer(data, dtype=np.uint8), cv2.IMREAD_COLOR)
    if frame is None:
        raise ImageError('compressed frame (%s) does not decode' % fmt)
    return frame


def task_frame(raw, compressed, max_pixels=MAX_PIXELS):
    """The array of a task's frame: ``compressed`` = ``(format, data)`` when it has data,
    else ``raw`` = ``(encoding, height, width, step, data)``. ImageError when it cannot be
    had or has more than ``max_pixels``."""
    fmt, blob = compressed
    if len(blob):
        return decode(fmt, blob, max_pixels)
    encoding, height, width, step, data = raw
    if height * width > max_pixels:
        raise ImageError('frame of %dx%d exceeds max_image_pixels %d' % (width, height, max_pixels))
    return to_array(encoding, height, width, step, data)


def convert(array, encoding):
    """``array`` (BGR or mono) with the channels ``encoding`` needs: mono for ``mono8``,
    BGR otherwise (the message conversion of :func:`from_array` does the rest)."""
    import cv2
    if encoding == 'mono8':
        return to_gray(array)
    return cv2.cvtColor(array, cv2.COLOR_GRAY2BGR) if np.ndim(array) == 2 else array
