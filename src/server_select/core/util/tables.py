"""Markdown tables, the one format every report, benchmark and summary prints."""

import statistics


def markdown_table(header, rows):
    """A Markdown table: ``header`` is a list of column titles, ``rows`` lists of cells.

    Cells are converted with ``str``; a row of the wrong length raises ValueError.
    """
    header = [str(h) for h in header]
    lines = ['| ' + ' | '.join(header) + ' |', '|' + '---|' * len(header)]
    for row in rows:
        cells = [str(c) for c in row]
        if len(cells) != len(header):
            raise ValueError('row %r has %d cells, the header %d' % (row, len(cells), len(header)))
        lines.append('| ' + ' | '.join(cells) + ' |')
    return '\n'.join(lines)


def fmt(value, spec='%.2f', missing='-'):
    """``spec % value``, or ``missing`` when the value is None."""
    return missing if value is None else spec % value


def median_range(values, spec='%.1f'):
    """``median (min-max)`` of repeated runs' ``values``; just the value for one run."""
    values = sorted(values)
    text = spec % statistics.median(values)
    return text + (' (%s-%s)' % (spec % values[0], spec % values[-1]) if len(values) > 1 else '')
