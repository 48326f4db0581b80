"""tools/rates_table.py, the docs' rate tables: rates per halving of h or of N^{-1/2} from a
summary.json, one row per variant (the p space included), and one line with exit 2 for a results
folder it cannot tabulate."""

import json

from ci_script import load

rates_table = load("tools/rates_table.py")


def case(level, p_space, e_u, e_p, e_l, unknowns):
    h = 0.5 ** level
    return {"level": level, "h": h, "u_space": "broken", "multiplier": "M1", "p_mass": "consistent",
            "p_space": p_space, "delta": 0.0, "unknowns": unknowns,
            "errors": {"u_l2": e_u, "p_l2": e_p, "p_x": e_p, "lambda_l2": e_l}}


def summary():
    """Two p spaces: errors C h^2, h, h^2 (and h^0.5 for the continuous p), N = 5 · 4^level."""
    cases = []
    for level in range(4):
        h, n = 0.5 ** level, 5 * 4 ** level
        cases.append(case(level, "broken-tangential", h ** 2, h, 3 * h ** 2, n))
        cases.append(case(level, "continuous", h, h ** 0.5, h, n))
    return {"cases": cases}


def rows(lines):
    return {line.split("|")[1].strip(): line for line in lines if line.startswith("| broken/")}


def test_rates_per_h_and_per_unknowns_are_the_orders_of_the_errors():
    for by in ("h", "unknowns"):
        r = rows(rates_table.table(summary(), by=by))
        assert set(r) == {"broken/M1/consistent/broken-tangential", "broken/M1/consistent/continuous"}
        cells = [c.strip() for c in r["broken/M1/consistent/broken-tangential"].split("|")[2:6]]
        assert cells == ["2.00, 2.00, 2.00", "1.00, 1.00, 1.00", "1.00, 1.00, 1.00",
                         "2.00, 2.00, 2.00"], (by, cells)
        cells = [c.strip() for c in r["broken/M1/consistent/continuous"].split("|")[2:6]]
        assert cells[1] == "0.50, 0.50, 0.50", (by, cells)


def test_a_summary_without_errors_is_one_line_and_exit_2(tmp_path, capsys):
    s = summary()
    for c in s["cases"]:
        del c["errors"]
    (tmp_path / "summary.json").write_text(json.dumps(s))
    assert rates_table.main([str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "no case has errors" in err[0]
    assert rates_table.main([str(tmp_path / "missing")]) == 2
