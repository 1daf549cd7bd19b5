"""``jaxdamp materials``: the material table (:mod:`jaxdamp.materials`) — what a name such as
``material = "steel"`` or ``wall = "glass"`` stands for, and where every number comes from."""

from __future__ import annotations

import argparse
import textwrap

EPILOG = textwrap.dedent(
    """\
    examples:
      jaxdamp materials
      jaxdamp materials --show glass

    A name is used in a configuration as material = "glass" in [[grains]], wall = "steel" in
    [box] or [container], or --set grains.0.material=glass; a table with name = "glass" and
    other keys (mu = 0.1) replaces single fields. Numbers marked * are estimates and ~
    substitutes (another pair): docs/materials.md gives every source.""")

_MARK = {"checked": "", "substitute": "~", "estimate": "*"}


def cmd_materials(args) -> int:
    from jaxdamp import materials
    from jaxdamp.cli.common import to_toml
    from jaxdamp.config import named_material

    if args.show:
        mat = named_material(args.show, "materials --show")
        entry = materials.lookup(args.show)
        print(f"# {entry.name}: {entry.description}")
        for field, datum in entry.data().items():
            at = f" at {entry.v_ref:g} m/s" if field == "restitution" else ""
            print(f"# {field} = {datum.value:g}{at} ({datum.status}): {datum.source}")
        print(f"# gamma_s = {mat.gamma_s:.6g}: the thesis steel's, carried over by "
              "jaxdamp.materials.tangential_damping (a modelling choice)")
        fields = {k: v for k, v in vars(mat).items() if v is not None}
        print(to_toml({"material": fields}, "grains.").strip("\n"))
        return 0
    print(f"{'name':17s} {'rho kg/m3':>9s} {'E GPa':>7s} {'nu':>5s} {'e vs steel':>15s} "
          f"{'mu vs steel':>11s}  description")
    for entry in materials.TABLE.values():
        e, mu = entry.restitution, entry.mu
        print(f"{entry.name:17s} {entry.density.value:9.0f} {entry.E.value / 1e9:7.1f} "
              f"{entry.nu.value:5.2f} {e.value:5.2f}{_MARK[e.status]:1s} at {entry.v_ref:g} m/s "
              f"{mu.value:10.2f}{_MARK[mu.status]:1s}  {entry.description}")
    print("* estimate, ~ substitute (another pair); every source: jaxdamp materials --show NAME "
          "or docs/materials.md")
    return 0


def register(sub) -> None:
    """Add the subcommand to the ``jaxdamp`` parser."""
    p = sub.add_parser("materials", help="list the material table (names for material = and "
                                         "wall =, with sources)",
                       description="List the materials a configuration may name "
                                   "(material = \"steel\", wall = \"glass\"): density, "
                                   "Young's modulus, Poisson ratio, restitution and friction "
                                   "against steel.",
                       epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--show", metavar="NAME", help="print one material's sources and the "
                                                  "[grains.material] table its name stands for")
    p.set_defaults(func=cmd_materials)
