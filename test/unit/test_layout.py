"""The package's shape: ROS-free layers stay ROS-free, modules (statements and lines) and
functions stay small."""

import ast
import os
import subprocess
import sys

import pytest

SRC = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..', 'src', 'server_select')
# Statements, not lines: a module cannot be kept under the limit by packing statements,
# nor pushed over it by documentation.
MAX_MODULE_STATEMENTS = 180
MAX_MODULE_LINES = 250      # and lines: a module a reader takes in at one sitting
MAX_FUNCTION_LINES = 50


def modules(*layers):
    for layer in layers or ('',):
        for root, _, files in os.walk(os.path.join(SRC, layer)):
            for name in sorted(files):
                if name.endswith('.py'):
                    yield os.path.join(root, name)


def module_name(path):
    rel = os.path.relpath(path, os.path.join(SRC, '..'))
    return rel[:-3].replace(os.sep, '.').replace('.__init__', '')


# what a ROS-free layer must not load: rospy, the ROS tools' libraries, generated code
ROS_MODULES = ('rospy', 'rospkg', 'rosgraph', 'genpy', 'server_select.msg', 'server_select.srv')


@pytest.mark.parametrize('layer', ['core', 'vision'])
def test_ros_free_layers_import_nothing_of_ros(layer):
    """Importing every module of the layer (in a fresh interpreter) loads no rospy, no
    rospkg, no rosgraph and no generated messages: it runs with no build and no master."""
    names = [module_name(p) for p in modules(layer)]
    code = ('import sys\nfor m in %r:\n    __import__(m)\n'
            'print(sorted(m for m in sys.modules if m.split(".")[0] in %r or m in %r))'
            % (names, ROS_MODULES, ROS_MODULES))
    out = subprocess.run([sys.executable, '-c', code], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, universal_newlines=True, check=False,
                         env=dict(os.environ, PYTHONPATH=os.pathsep.join(
                             [os.environ.get('PYTHONPATH', ''), os.path.dirname(SRC)])))
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == '[]', '%s imports %s' % (layer, out.stdout)


def statements(path):
    with open(path) as stream:
        tree = ast.parse(stream.read(), path)
    return sum(1 for node in ast.walk(tree) if isinstance(node, ast.stmt))


def test_statements_are_counted():
    """Two statements on a line are two; a docstring is one, however long."""
    assert statements(__file__) > 20
    code = 'def f():\n    """A\n\n    long doc."""\n    a = 1; b = 2\n    return a + b\n'
    assert sum(1 for n in ast.walk(ast.parse(code)) if isinstance(n, ast.stmt)) == 5


def test_modules_are_short():
    long = dict((module_name(p), n) for p in modules()
                for n in [statements(p)] if n > MAX_MODULE_STATEMENTS)
    assert long == {}
    with_lines = {}
    for path in modules():
        with open(path) as stream:
            lines = sum(1 for _ in stream)
        if lines > MAX_MODULE_LINES:
            with_lines[module_name(path)] = lines
    assert with_lines == {}


def test_functions_are_short():
    long = {}
    for path in modules():
        with open(path) as stream:
            tree = ast.parse(stream.read(), path)
        for node in ast.walk(tree):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                length = node.end_lineno - node.lineno + 1
                if length > MAX_FUNCTION_LINES:
                    long['%s.%s' % (module_name(path), node.name)] = length
    assert long == {}


def test_nothing_finds_files_above_the_package():
    """Installed packages have no ``../../config``: files are found through the package."""
    offenders = [module_name(p) for p in modules() if "'..', '..'" in open(p).read()]
    assert offenders == []


# core's topics, each importing only those before it (core/__init__.py says what each owns)
CORE_ORDER = ('util', 'config', 'trust', 'load', 'ranking', 'rule', 'peers', 'manager', 'flow',
              'fleet', 'robot', 'settings', 'observe')


def core_imports():
    """``{(importing topic, imported topic)}`` of core's modules (a topic is a sub-package,
    or the ``settings`` module)."""
    found = set()
    for path in modules('core'):
        rel = os.path.relpath(path, os.path.join(SRC, 'core')).split(os.sep)
        topic = rel[0] if len(rel) > 1 else rel[0][:-3]
        with open(path) as stream:
            tree = ast.parse(stream.read(), path)
        for node in ast.walk(tree):
            names = [node.module or ''] if isinstance(node, ast.ImportFrom) else \
                [a.name for a in node.names] if isinstance(node, ast.Import) else []
            for name in names:
                parts = name.split('.')
                if parts[:2] == ['server_select', 'core'] and len(parts) > 2 \
                        and parts[2] != topic:
                    found.add((topic, parts[2]))
    return found


def test_core_topics_import_only_those_below_them():
    assert {'ranking', 'config', 'settings'} <= set(t for pair in core_imports() for t in pair)
    upward = sorted((a, b) for a, b in core_imports()
                    if b not in CORE_ORDER or a not in CORE_ORDER
                    or CORE_ORDER.index(b) >= CORE_ORDER.index(a))
    assert upward == []
    topics = set(name[:-3] if name.endswith('.py') else name
                 for name in os.listdir(os.path.join(SRC, 'core'))
                 if name not in ('__init__.py', '__pycache__'))
    assert topics == set(CORE_ORDER)


def imports_of(path):
    """The package's modules that ``path`` imports (anywhere in it, in functions too)."""
    with open(path) as stream:
        tree = ast.parse(stream.read(), path)
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and (node.module or '').startswith('server_select'):
            found.update('%s.%s' % (node.module, a.name) for a in node.names)
            found.add(node.module)
        elif isinstance(node, ast.Import):
            found.update(a.name for a in node.names if a.name.startswith('server_select'))
    return found


def test_no_module_imports_itself_through_others():
    """No import cycle in the package (a cycle is a module two layers claim)."""
    graph = dict((module_name(p), imports_of(p)) for p in modules())
    graph = dict((m, set(i for i in deps if i in graph and i != m)) for m, deps in graph.items())
    cycles, done = [], set()

    def visit(module, path):
        if module in path:
            cycles.append(path[path.index(module):] + [module])
            return
        if module in done:
            return
        for dep in sorted(graph[module]):
            visit(dep, path + [module])
        done.add(module)
    for module in sorted(graph):
        visit(module, [])
    assert cycles == []


# the package's layers, each importing only those before it (generated messages aside)
LAYERS = ('core', 'vision', 'ros', 'tasks', 'testbed', 'nodes', 'bench')


def test_layers_import_only_those_below_them():
    """One import direction between the layers: ``ros/`` knows no task type, ``tasks/`` no
    node, nothing below the testbed or the nodes a benchmark."""
    upward = set()
    for path in modules():
        layer = (module_name(path).split('.') + [''])[1]
        if layer not in LAYERS:
            continue
        for name in imports_of(path):
            used = name.split('.')[1] if name.count('.') else ''
            if used in LAYERS and LAYERS.index(used) > LAYERS.index(layer):
                upward.add((layer, used))
    assert sorted(upward) == []


def test_no_node_keeps_data_under_the_name_the_runner_starts_it_by():
    """``ros.runner`` calls a node's ``start()`` once it is built: a node that stored a
    number as ``self.start`` died at start (the search monitor did)."""
    offenders = []
    for path in modules('nodes'):
        with open(path) as stream:
            tree = ast.parse(stream.read(), path)
        for node in ast.walk(tree):
            if isinstance(node, ast.Assign) and any(
                    isinstance(t, ast.Attribute) and t.attr == 'start' and
                    isinstance(t.value, ast.Name) and t.value.id == 'self'
                    for t in node.targets):
                offenders.append('%s:%d' % (module_name(path), node.lineno))
    assert offenders == []
