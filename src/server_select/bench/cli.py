"""What every benchmark's command line shares: its parser (the module's summary as the
description, ``--out``) and how it writes its results there."""

import argparse
import json
import os


def parser(doc, out='results/bench'):
    """An ArgumentParser described by the first paragraph of ``doc``, with ``--out``."""
    parsed = argparse.ArgumentParser(description=doc.split('\n\n')[0])
    parsed.add_argument('--out', default=out, help='folder for the results (default: %s)'
                        % out)
    return parsed


def messages(parsed, count, interval=0.01, size=4):
    """``--count``, ``--size`` (bytes) and ``--interval`` (s) of a stream of timed
    messages, added to the (sub)parser ``parsed``; returns it."""
    parsed.add_argument('--count', type=int, default=count)
    parsed.add_argument('--size', type=int, default=size)
    parsed.add_argument('--interval', type=float, default=interval)
    return parsed


def write(out, name, data):
    """``data`` to ``out/name`` (JSON for a ``.json`` name, else text); returns the path."""
    os.makedirs(out, exist_ok=True)
    path = os.path.join(out, name)
    with open(path, 'w') as stream:
        if name.endswith('.json'):
            json.dump(data, stream, indent=1)
        else:
            stream.write(data)
    return path
