"""``wbsa bsa``: every classical BSA formula for one height and weight."""

from __future__ import annotations

import argparse
import sys

from wbsa.formulae.validate import HEIGHT_RANGE_CM, WEIGHT_RANGE_KG


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``bsa`` subcommand to the ``wbsa`` parser."""
    h_lo, h_hi = HEIGHT_RANGE_CM
    w_lo, w_hi = WEIGHT_RANGE_KG
    parser = subparsers.add_parser(
        "bsa",
        help="body surface area from height and weight by every classical formula",
        description=(
            "Print the body surface area (m²) given by every classical formula (Du Bois, Mosteller, Haycock, "
            "Gehan & George, Boyd, Fujimoto, Takahira, Shuter & Aslani, Schlich, Yu, Livingston & Lee, "
            f"Tikuisis). Accepted range: height {h_lo:g}–{h_hi:g} cm, weight {w_lo:g}–{w_hi:g} kg."
        ),
    )
    parser.add_argument("--height-cm", type=float, required=True, metavar="H", help="stature in centimetres, e.g. 170")
    parser.add_argument("--weight-kg", type=float, required=True, metavar="W", help="body mass in kilograms, e.g. 70")
    parser.add_argument(
        "--sex",
        choices=("male", "female"),
        default=None,
        help="selects the Schlich coefficients; without it both the male and the female values are shown",
    )
    parser.add_argument(
        "--formula",
        action="append",
        metavar="NAME",
        help="only this formula (repeatable); a key such as dubois or a name users know, any case: Mosteller, "
        "DuBois-DuBois, Gehan-George (R admiral), bsa_dubois_dubois (R physiology)",
    )
    parser.add_argument("--json", action="store_true", help="print a JSON object instead of a table")
    parser.set_defaults(func=handle)


def handle(args: argparse.Namespace) -> int:
    """Compute and print every formula; a bad height or weight raises :class:`~wbsa.errors.WbsaError`."""
    from wbsa.formulae.catalogue import FORMULAE
    from wbsa.formulae.compute import bsa, bsa_all
    from wbsa.formulae.names import formula_key

    if args.formula:
        keys = dict.fromkeys(formula_key(name) for name in args.formula)  # unknown names fail before any output
        if args.sex is None and "schlich" in keys:  # as in the full table: Schlich at both sexes
            both = ("schlich_male", "schlich_female")
            keys = dict.fromkeys(k for key in keys for k in (both if key == "schlich" else (key,)))
        values = {key: float(bsa(key, args.height_cm, args.weight_kg, args.sex)) for key in keys}
    else:
        values = {key: float(v) for key, v in bsa_all(args.height_cm, args.weight_kg, args.sex).items()}
    if args.json:
        payload = {"height_cm": args.height_cm, "weight_kg": args.weight_kg, "sex": args.sex, "bsa_m2": values}
        from wbsa.strict_json import json_text

        sys.stdout.write(json_text(payload) + "\n")
        return 0
    rows = []
    for key, value in values.items():
        if key in FORMULAE:
            formula = FORMULAE[key]
            sex_label = args.sex if formula.sex_specific else None
        else:  # schlich_male / schlich_female: Schlich at a fixed sex
            formula = FORMULAE["schlich"]
            sex_label = key.removeprefix("schlich_")
        name = f"{formula.name} ({sex_label})" if sex_label else formula.name
        rows.append((name, str(formula.year), f"{value:.4f}"))
    header = ("formula", "year", "BSA (m²)")
    widths = [max(len(r[i]) for r in (header, *rows)) for i in range(3)]
    sys.stdout.write(
        f"height {args.height_cm:g} cm, weight {args.weight_kg:g} kg" + (f", {args.sex}" if args.sex else "") + "\n"
    )
    for name, year, value in (header, *rows):
        sys.stdout.write(f"{name:<{widths[0]}}  {year:>{widths[1]}}  {value:>{widths[2]}}\n")
    return 0
