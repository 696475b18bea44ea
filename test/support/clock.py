"""A clock the tests move by hand (what the ROS-free classes take as ``clock``)."""


class Clock(object):
    def __init__(self, now=100.0):
        self.now = now

    def __call__(self):
        return self.now
