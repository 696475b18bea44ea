"""A task type for server_select, outside it: ``task_plugins:=wordcount_task.tasks:WordCount``
on robots and servers.

Robot side: every ``1 / rate`` s a sentence (setting ``text``, with the task id appended so
that each task differs) goes to the selected server; the result's count is checked. Server
side: the words are counted. Selection, failover, busy answers and one ``task_report`` per
task come from server_select.
"""

from std_msgs.msg import Header

from server_select.ros.plugins import TaskPlugin
from wordcount_task.msg import WordCountResult, WordCountTask


class WordCount(TaskPlugin):
    """Counts the words of a sentence."""

    kind = 'wordcount'                 # in task reports, and the settings' namespace
    task_type, result_type = WordCountTask, WordCountResult
    task_topic, result_topic = 'task_wordcount', 'processed_wordcount'

    def __init__(self, robot_id, settings):
        super(WordCount, self).__init__(robot_id, settings)
        self.text = str(settings.get('text', 'hello world'))
        if robot_id is not None and not self.text.split():
            raise ValueError('text: at least one word')      # refused at start-up, by name

    def make(self, task_id, stamp):
        """``(request, context)``: the context is what :meth:`check` gets with the result."""
        text = '%s %d' % (self.text, task_id)
        return WordCountTask(header=Header(stamp=stamp), robot_id=self.robot_id,
                             task_id=task_id, text=text), len(text.split())

    def check(self, result, expected):
        """Why an ok result is wrong (None: it is right)."""
        if result.words != expected:
            return 'counted %d words, expected %d' % (result.words, expected)
        return None

    def run_local(self, task_id, stamp):
        """Mode ``local``: the work on the robot itself; an error string or None."""
        len(('%s %d' % (self.text, task_id)).split())
        return None

    def handle(self, task, result):
        """Server side: fill ``result`` (raise ValueError to reject the task)."""
        if len(task.text) > 100000:
            raise ValueError('text longer than 100000 characters')
        result.words = len(task.text.split())

    rehearse = handle     # it acts on its result alone: an idle server may time a copy
