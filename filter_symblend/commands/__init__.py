"""The ``symblend`` command, one module per subcommand; ``main`` builds the parser and runs one. It
symmetrizes a mesh from a landmark file or a whole study, runs filter scripts, compares before and after,
and checks and converts landmarks.

    symblend symmetrize INPUT -l LANDMARKS -o OUTPUT [--pair-table PAIRS.csv] [--curves] [--report REPORT.json] [filter options]
    symblend symmetrize INPUT --pairs auto -o OUTPUT [--report REPORT.json] [filter options]
    symblend batch MANIFEST.csv -o OUTDIR [--workers N] [--scheduler ADDRESS] [--force] [symmetrize options]
    symblend mlx SCRIPT.mlx INPUT [-l LANDMARKS] -o OUTPUT [--report REPORT.json]
    symblend report BEFORE AFTER [--png PICTURE.png] [--json NUMBERS.json]
    symblend landmarks check INPUT -l LANDMARKS [--pair-table PAIRS.csv]
    symblend landmarks convert IN OUT [--specimen ID|INDEX]

The filter options are generated from the filter's parameter declaration.
Errors are one line on stderr and nothing is written; exit status 1 bad input, 2 usage, 130 interrupted.
"""

from .start import quiet_interrupt_while_loading

quiet_interrupt_while_loading()  # first: acts only in the symblend command's own process

