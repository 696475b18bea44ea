"""ORB keypoints and descriptors of a frame (no rospy): a SLAM front end's first step."""

from server_select.core.util.lazy import deferred
from server_select.vision.image_codec import to_gray

np = deferred('numpy')


def orb_features(frame, max_features=500):
    """``(points, descriptors)``: an (N, 2) float32 array of keypoint positions and an
    (N, 32) uint8 array of their binary descriptors, N <= ``max_features``."""
    import cv2    # lazy: no OpenCV in a node that needs none
    orb = cv2.ORB_create(nfeatures=max(1, int(max_features)))
    keypoints, descriptors = orb.detectAndCompute(to_gray(frame), None)
    if descriptors is None or not keypoints:
        return np.zeros((0, 2), np.float32), np.zeros((0, 32), np.uint8)
    points = np.array([k.pt for k in keypoints], dtype=np.float32)
    return points, descriptors.astype(np.uint8)
