"""What the scorer expects of metrocell's JSON (issue 27; the commands are being built), read
tolerantly where the names are not fixed yet, and failing with the path it looked for when a
field is missing.

`calibrate --json`: a top-level `check` section, per model and per setup and over all,
    check.<declared|fitted>.<overall|setups.<name>> = {n, rms_m, p50_xy_m, p95_xy_m, p95_z_m, max_m}
Accepted spellings (first found wins): model `nominal`/`rigid`/`declared` (metrocell: `nominal` is the kinematics alone, `declared` the model file's values), `fitted`/`calibrated`; over
all `overall`/`all`/`total`; per setup `setups`/`per_setup`/`by_setup` (a dict by name or a
list of entries with `setup`/`name`).
`diagnose --json`: `findings[*].term` (crates/diagnose/README.md).
"""

import math

STAT_FIELDS = ("n", "rms_m", "p50_xy_m", "p95_xy_m", "p95_z_m", "max_m")
REQUIRED = ("n", "p50_xy_m", "p95_xy_m", "p95_z_m")
MODEL_KEYS = {"declared": ("nominal", "rigid", "declared"), "fitted": ("fitted", "calibrated")}
OVERALL_KEYS = ("overall", "all", "total")
SETUP_KEYS = ("setups", "per_setup", "by_setup")


class ContractError(Exception):
    """A command's output lacks what the workflow needs: the message names the path."""


def _first(d, keys):
    for k in keys:
        if isinstance(d, dict) and k in d:
            return k, d[k]
    return None, None


def _stats(obj, where):
    if not isinstance(obj, dict):
        raise ContractError(f"{where}: expected an object {{{', '.join(STAT_FIELDS)}}}, found {type(obj).__name__}")
    missing = [f for f in REQUIRED if f not in obj]
    if missing:
        raise ContractError(f"{where}: missing {', '.join(missing)} (has: {', '.join(sorted(obj)) or 'nothing'})")
    for f in REQUIRED[1:]:
        v = obj[f]
        if v is not None and not (isinstance(v, (int, float)) and math.isfinite(v)):
            raise ContractError(f"{where}.{f}: not a finite number ({v!r})")
    return {f: obj.get(f) for f in STAT_FIELDS}


def read_check(j, source):
    """{declared|fitted: {overall: stats, setups: {name: stats}}} from calibrate's JSON."""
    if not isinstance(j, dict) or "check" not in j:
        keys = ", ".join(sorted(j)) if isinstance(j, dict) else type(j).__name__
        raise ContractError(f"{source}: no top-level `check` section (issue 27: check.<declared|fitted>.<overall|setups>); "
                            f"top-level keys: {keys}")
    check = j["check"]
    out = {}
    for model, spellings in MODEL_KEYS.items():
        key, section = _first(check, spellings)
        if section is None:
            raise ContractError(f"{source}: check has no `{spellings[0]}` section (accepted: {', '.join(spellings)}; "
                                f"has: {', '.join(sorted(check)) if isinstance(check, dict) else check!r})")
        okey, overall = _first(section, OVERALL_KEYS)
        if overall is None:
            raise ContractError(f"{source}: check.{key} has no `overall` statistics (accepted: {', '.join(OVERALL_KEYS)})")
        skey, setups = _first(section, SETUP_KEYS)
        per = {}
        if isinstance(setups, dict):
            per = {name: _stats(v, f"{source}: check.{key}.{skey}.{name}") for name, v in setups.items()}
        elif isinstance(setups, list):
            for i, v in enumerate(setups):
                name = v.get("setup", v.get("name", f"#{i}")) if isinstance(v, dict) else f"#{i}"
                per[name] = _stats(v, f"{source}: check.{key}.{skey}[{i}]")
        out[model] = {"overall": _stats(overall, f"{source}: check.{key}.{okey}"), "setups": per}
    return out


def finding_terms(j, source):
    if not isinstance(j, dict) or "findings" not in j:
        raise ContractError(f"{source}: no `findings` (crates/diagnose/README.md)")
    return [f.get("term") for f in j["findings"] or []]


def parameter_entries(obj, path=""):
    """Every {value[, sigma]} object in a JSON tree: [(path, value, sigma)]."""
    out = []
    if isinstance(obj, dict):
        if isinstance(obj.get("value"), (int, float)) and not isinstance(obj.get("value"), bool):
            s = obj.get("sigma", obj.get("uncertainty"))
            out.append((path, float(obj["value"]), float(s) if isinstance(s, (int, float)) else None))
        for k, v in obj.items():
            out += parameter_entries(v, f"{path}/{k}")
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            label = v.get("label") or v.get("name") or v.get("term") if isinstance(v, dict) else None
            out += parameter_entries(v, f"{path}[{label if label else i}]")
    return out
