"""The benchmarks' and the soak's camera driver: a 640 x 480 JPEG photograph on a
CompressedImage topic at a fixed rate, stamped, frame_id ``camera``, registering again with
a restarted roscore as the package's nodes do.

    python -m server_select.bench.camera TOPIC RATE
"""

import sys
import time

import cv2
import rospy
from sensor_msgs.msg import CompressedImage

from server_select.core.config import names
from server_select.ros.master_watch import MasterWatch
from server_select.vision.search import sample_image


def publish(topic, rate):
    """Publish on ``topic`` at ``rate`` Hz until shut down."""
    rospy.init_node('camera')
    frame = cv2.resize(sample_image('astronaut.png'), (640, 480))
    jpeg = cv2.imencode('.jpg', frame, [cv2.IMWRITE_JPEG_QUALITY, 80])[1].tobytes()
    pub = rospy.Publisher(topic, CompressedImage, queue_size=1)
    MasterWatch(5.0, topic=names.MASTER_PID_TOPIC).start()
    period, due = 1.0 / float(rate), time.monotonic()
    while not rospy.is_shutdown():
        msg = CompressedImage(format='bgr8; jpeg compressed bgr8', data=jpeg)
        msg.header.stamp, msg.header.frame_id = rospy.Time.now(), 'camera'
        pub.publish(msg)
        due += period
        time.sleep(max(0.0, due - time.monotonic()))
    return 0


def main(argv=None):
    topic, rate = (argv or sys.argv[1:])[:2]
    return publish(topic, rate)


if __name__ == '__main__':
    sys.exit(main())
