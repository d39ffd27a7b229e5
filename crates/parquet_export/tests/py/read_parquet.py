"""Read a Parquet file with pyarrow and print its schema and columns as JSON.

Usage: read_parquet.py FILE. Prints {"rows": N, "names": [columns in file order], "types": {column: arrow type text},
"columns": {column: [values...]}}; floats keep their exact value (Python's repr round-trips).
"""
import json
import sys

import pyarrow.parquet as pq


def main(path):
    table = pq.read_table(path)
    doc = {
        'rows': table.num_rows,
        'names': table.column_names,
        'types': {f.name: str(f.type) for f in table.schema},
        'columns': {name: table.column(name).to_pylist() for name in table.column_names},
    }
    json.dump(doc, sys.stdout)


if __name__ == '__main__':
    main(sys.argv[1])
