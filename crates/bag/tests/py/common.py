"""Shared helpers for the bag interop scripts: turn decoded ROS messages into JSON."""
import json
import sys


def to_plain(obj):
    """Recursively convert a decoded message (dataclass / namedtuple / numpy) to JSON types."""
    if hasattr(obj, 'tolist'):
        return obj.tolist()
    if hasattr(obj, '__dataclass_fields__'):
        return {k: to_plain(getattr(obj, k)) for k in obj.__dataclass_fields__ if k != '__msgtype__'}
    if hasattr(obj, '__slots__') and not isinstance(obj, (str, bytes)):
        return {k: to_plain(getattr(obj, k)) for k in obj.__slots__ if not k.startswith('_')}
    if isinstance(obj, (list, tuple)):
        return [to_plain(x) for x in obj]
    if isinstance(obj, bytes):
        return list(obj)
    return obj


def emit(doc):
    json.dump(doc, sys.stdout)
    sys.stdout.write('\n')
