"""Launch arguments no launch file declares (``probe_rat:=5``), which roslaunch ignores
without a word: named, with the nearest declared argument, by the first node of this
package that the launch starts (one line per argument, not one per node).

The launch is read the way roslaunch reads it (its own option parser and XML loader) from
the command line of the roslaunch process that started this node.
"""

import os

import rosgraph.names

from server_select.core.config.params import nearest

ROSLAUNCH = b'roslaunch'


def parent_roslaunch_argv(pid=None):
    """The command line of the roslaunch process that started this one (str), or None."""
    parent = os.getppid() if pid is None else pid
    try:
        with open('/proc/%d/cmdline' % parent, 'rb') as stream:
            argv = stream.read().rstrip(b'\0').split(b'\0')
    except OSError:
        return None
    for i, arg in enumerate(argv[:2]):
        if os.path.basename(arg) == ROSLAUNCH:
            return [a.decode(errors='replace') for a in argv[i:]]
    return None


def undeclared(argv):
    """``(first node, [(argument, nearest declared one or None)])`` of roslaunch's
    ``argv``: the full name of the first node of this package the launch starts (None if
    none), and the ``name:=value`` arguments no launch file of it declares (an argument
    declared by a file that another includes without ``pass_all_args`` counts as
    declared: this check names no argument that works)."""
    import roslaunch
    import roslaunch.config
    import roslaunch.rlutil
    import roslaunch.xmlloader
    _, args = roslaunch._get_optparse().parse_args(argv[1:])
    given = [a.split(':=', 1)[0] for a in args if ':=' in a and not a.startswith('_')]
    files = roslaunch.rlutil.resolve_launch_arguments([a for a in args if ':=' not in a])
    declared = set()

    class Loader(roslaunch.xmlloader.XmlLoader):
        """Every ``<arg>`` of the launch tree counts: an included file's reaches the
        command line through ``pass_all_args``."""
        def _arg_tag(self, tag, *args, **kwargs):
            declared.add(tag.getAttribute('name'))
            return super(Loader, self)._arg_tag(tag, *args, **kwargs)

    loader = Loader(resolve_anon=False)
    config = roslaunch.config.ROSLaunchConfig()
    for path in files:
        loader.load(path, config, argv=argv, verbose=False)
    first = next((rosgraph.names.ns_join(n.namespace, n.name) for n in config.nodes
                  if n.package == 'server_select'), None)
    return first, [(name, nearest(name, declared)) for name in given if name not in declared]


def warn_undeclared(node_name, log):
    """If this node is the launch's first of the package: ``log`` one line per launch
    argument no launch file declares. Quiet (and no cost) when not started by roslaunch;
    a launch it cannot read again is left to roslaunch."""
    argv = parent_roslaunch_argv()
    if argv is None:
        return
    try:
        first, unknown = undeclared(argv)
    except Exception:       # roslaunch started it, so the launch was readable then
        return
    if first != node_name:
        return
    for name, near in unknown:
        log('%s: launch argument %s:= is declared by no launch file of this launch, so it '
            'sets nothing%s' % (node_name, name, '; did you mean %s:=?' % near
                                if near else ''))
