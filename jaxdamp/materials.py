"""The material table: grains and walls by name (``material = "steel"`` in ``[[grains]]``,
``wall = "steel"`` in ``[box]`` or ``[container]``), with the source of every number
(docs/materials.md).

Each :class:`Entry` holds, for one material, its density ``ρ`` [kg/m³], Young's modulus ``E``
[Pa], Poisson ratio ``ν`` [-], the coefficient of restitution ``e`` [-] of a head-on impact
against steel at the speed ``v_ref`` [m/s], and the kinetic (sliding) friction coefficient
``μ`` [-] against steel, unlubricated. Every number is a :class:`Datum` with its source and a
status:

* ``checked`` — read, while the table was written, in a text whose address is given;
* ``substitute`` — a sourced value of a neighbouring pair (e.g. against cast iron where no value
  against steel was found), named as such;
* ``estimate`` — no source was found: a labelled estimate, justified in its source text.

**How the table maps onto jaxdamp's contact model** (docs/materials.md, "Mapping"):
:meth:`Entry.fields` gives the keyword arguments of :class:`jaxdamp.config.Material`:
``restitution = e`` at ``v_ref`` (jaxdamp calibrates it on the like-pair, grain–grain collision:
the impact against steel stands for the impact of two grains of the material), ``mu = μ``
(the mixing rule ``Config.mixing`` combines it with the partner's ``μ``), and the tangential
viscous constant ``gamma_s`` from :func:`tangential_damping`, without which the Coulomb
friction of jaxdamp's tangential law would not act at all
(``F_t = -min(γ_s sqrt(ξ)|v_s|, μ F_n)``).

This module imports nothing from jaxdamp (:mod:`jaxdamp.config` imports it to resolve names).
"""

from __future__ import annotations

from dataclasses import dataclass

CHECKED = "checked"
SUBSTITUTE = "substitute"
ESTIMATE = "estimate"
STATUSES = (CHECKED, SUBSTITUTE, ESTIMATE)


@dataclass(frozen=True)
class Datum:
    """One number of the table.

    Attributes:
      value: the number, SI units.
      status: :data:`CHECKED`, :data:`SUBSTITUTE` or :data:`ESTIMATE` (module docstring).
      source: author, year, title/handbook, table — and the address of the text it was read in
        (``checked``, ``substitute``), or the justification of an ``estimate``.
    """

    value: float
    status: str
    source: str


@dataclass(frozen=True)
class Entry:
    """A material of the table.

    Attributes:
      name: its name in a configuration (lower case).
      description: what the name stands for (grade, condition).
      density: ``ρ`` [kg/m³].
      E: Young's modulus [Pa].
      nu: Poisson ratio [-].
      restitution: coefficient of restitution [-] of a head-on impact against steel at
        ``v_ref``.
      v_ref: the impact speed [m/s] of ``restitution``.
      mu: kinetic friction coefficient [-] against steel, unlubricated.
    """

    name: str
    description: str
    density: Datum
    E: Datum
    nu: Datum
    restitution: Datum
    v_ref: float
    mu: Datum

    def data(self) -> dict[str, Datum]:
        """The sourced numbers by field name (``density``, ``E``, ``nu``, ``restitution``,
        ``mu``)."""
        return {"density": self.density, "E": self.E, "nu": self.nu,
                "restitution": self.restitution, "mu": self.mu}

    def fields(self) -> dict[str, float]:
        """The keyword arguments of :class:`jaxdamp.config.Material` this entry resolves to:
        ``E``, ``nu``, ``density``, ``mu``, ``restitution``, ``v_ref`` and ``gamma_s``
        (:func:`tangential_damping`); the normal damping is the restitution's (``gamma_n`` unset),
        calibrated at the species' radius (``calibration_radius`` unset)."""
        return {"E": self.E.value, "nu": self.nu.value, "density": self.density.value,
                "mu": self.mu.value, "restitution": self.restitution.value,
                "v_ref": self.v_ref,
                "gamma_s": tangential_damping(self.E.value, self.nu.value, self.density.value)}


# -------------------------------------------------------------------------------------------
# The tangential viscous constant

#: The thesis' steel (Sánchez 2012, §3.2; ``jaxdamp.cases.presets.SANCHEZ_STEEL`` is made of
#: these): ``E`` [Pa], ``ν``, ``ρ`` [kg/m³] and ``γ_s`` [kg s⁻¹ m⁻½].
THESIS_E, THESIS_NU, THESIS_DENSITY, THESIS_GAMMA_S = 2.03e11, 0.28, 8030.0, 10980.0


def tangential_damping(E: float, nu: float, density: float) -> float:
    """``γ_s`` [kg s⁻¹ m⁻½] of a table material: the thesis steel's ``γ_s`` carried over so
    that a like-pair collision of the material has the thesis steel's dimensionless tangential
    damping at equal radius and speed (docs/physics.md §2, "Reduced modulus"),

        c_s = γ_s v^{1/5} / (k^{3/5} m*^{2/5}),   k ∝ E* = E / (2 (1 - ν²)),   m* ∝ ρ
        ⇒  γ_s = γ_s,thesis (E* / E*_thesis)^{3/5} (ρ / ρ_thesis)^{2/5}.

    A modelling choice (no source gives ``γ_s`` per material), stated in docs/materials.md;
    thesis steel gives back 10980."""
    e_star = E / (2.0 * (1.0 - nu * nu))
    e_thesis = THESIS_E / (2.0 * (1.0 - THESIS_NU * THESIS_NU))
    return THESIS_GAMMA_S * (e_star / e_thesis) ** 0.6 * (density / THESIS_DENSITY) ** 0.4


# -------------------------------------------------------------------------------------------
# Sources (the texts read while the table was written, 2026-12; addresses as retrieved)

_WYPYCH = ("G. Wypych, Handbook of Surface Improvement and Modification (ChemTec, 2018), "
           "Table 11.1 'Friction coefficients of common materials', dynamic column "
           "(digilib.universitaspertamina.ac.id/ebook/Handbook of Surface Improvement and "
           "Modification, page 172)")
_NO_E = ("no measured restitution against steel was found in the texts we could retrieve "
         "(measurements exist inside papers we could not read; searched a second time in "
         "stored web pages, documentation and code: of Kharaz & Gorham 2000, Gorham & "
         "Kharaz 2000 (Powder Technol. 112:193), Kharaz, Gorham & Salman 2001, Sondergaard "
         "et al. 1990, Foerster et al. 1994, Gondret et al. 2002 and the survey of Güttler "
         "et al. 2012 (arXiv:1204.0001) only titles, abstracts or first pages could be read, "
         "none with a value, and of Mok & Duffy 1964 nothing; docs/materials.md)")
_HARD = (f"{_NO_E}; a hard, nearly elastic pair at 1 m/s (no yield of the ball, "
         "small plastic and vibration losses), the same 0.9 for every hard entry without a "
         "substitute")
_DUCTILE = (f"{_NO_E}; a ductile metal that yields at a tenth of hardened steel's "
            "yield strength loses more in plastic indentation than a hard pair: 0.8")
_NO_MU = ("no kinetic friction coefficient against steel was found in the texts we "
          "could retrieve (searched a second time; what was found is named here); steel on "
          "steel's 0.23 of the same table (Wypych 2018, Table 11.1: its dynamic values of "
          "metals on steel lie at 0.21-0.25), for a hard pair")
_52100 = ("AISI 52100 datasheet (AZoM data as reproduced at www.stindia.com/article/"
          "difference-between/difference-between-52100-e52100-steel.html)")

#: The materials by name.
TABLE: dict[str, Entry] = {e.name: e for e in (
    Entry(
        name="steel",
        description="bearing steel AISI 52100 (100Cr6, SUJ2), hardened: the usual steel ball",
        density=Datum(7810.0, CHECKED, f"{_52100}: density 7.81 g/cm³"),
        E=Datum(2.03e11, CHECKED, "'AISI 52100 Chrome Steel' ball datasheet (www.scribd.com/"
                "document/252517093): modulus of elasticity 29,500,000 psi = 2.03e11 Pa; "
                f"within the 190-210 GPa of the {_52100}"),
        nu=Datum(0.28, CHECKED, f"{_52100}: 0.27-0.30; 0.28 is also the thesis' steel "
                 "(Sánchez 2012, §3.2)"),
        restitution=Datum(0.9, ESTIMATE, f"{_HARD}; a small steel ball on a heavy polished "
                          "steel plate 'bounces dozens of times' (demoweb.physics.ucla.edu/"
                          "content/20-coefficient-restitution): qualitative, no value"),
        v_ref=1.0,
        mu=Datum(0.23, CHECKED, f"{_WYPYCH}: steel-steel 0.31 static, 0.23 dynamic; the same "
                 "as J. R. Davis, Concise Metals Data Handbook (ASM, 1995), Table 14.1, 0.23 "
                 "sliding, as quoted at www-eng.lbl.gov/~ajdemell/coefficients_of_friction.html"),
    ),
    Entry(
        name="stainless",
        description="austenitic stainless steel AISI 304 (1.4301), annealed",
        density=Datum(8000.0, CHECKED, "'AISI Type 304 Stainless Steel' datasheet (MatWeb "
                      "format, www.scribd.com/document/416534641): density 8 g/cc"),
        E=Datum(1.93e11, CHECKED, "the same datasheet: modulus of elasticity 193-200 GPa (the "
                "lower end)"),
        nu=Datum(0.29, CHECKED, "the same datasheet: Poisson's ratio 0.29"),
        restitution=Datum(0.8, ESTIMATE, f"{_DUCTILE} (its yield strength 215 MPa, the same "
                          "datasheet, against 2030 MPa of the 52100 ball datasheet)"),
        v_ref=1.0,
        mu=Datum(0.23, ESTIMATE, f"{_NO_MU}; the nearest pair found is copper on 304 "
                 "stainless, dry, 0.23 static, 0.21 sliding (www-eng.lbl.gov/~ajdemell/"
                 "coefficients_of_friction.html): another material on stainless, not used"),
    ),
    Entry(
        name="tungsten-carbide",
        description="cemented tungsten carbide (WC-Co)",
        density=Datum(15000.0, CHECKED, "makeitfrom.com, 'Tungsten Carbide (WC)' (fracture "
                      "toughness 12 MPa m^1/2: a cemented grade): density 15 g/cm³"),
        E=Datum(6.3e11, CHECKED, "the same page: elastic modulus 630 GPa (Wikipedia, "
                "'Tungsten carbide': 530-700 GPa)"),
        nu=Datum(0.24, CHECKED, "the same page: Poisson's ratio 0.24"),
        restitution=Datum(0.89, SUBSTITUTE, "Leeb rebound hardness test, impact device D: "
                          "HL = 1000 v_rebound/v_impact, and the hardest sample device D "
                          "measures gives 890 HLD (~68 HRC, ~955 HV) (Proceq, Equotip 3 "
                          "operating instructions, 2012, §2.1 and §2.3, as reproduced at "
                          "manualshive.com/ru/manual/proceq/equotip-3/1608675?page=5); device "
                          "D's impact body: 5.5 g, 3 mm tungsten-carbide ball tip, 11 mJ "
                          "(calspec.com.au/product/the-impact-device-of-hardness-tester), so "
                          "v_impact = sqrt(2 x 0.011 J / 0.0055 kg) = 2.0 m/s: e = 0.89 of a "
                          "WC-tipped impact body against 68-HRC steel at 2.0 m/s. A substitute: "
                          "the impactor is a tipped rod, not a free sphere, and softer steel "
                          "gives a lower HL (Wikipedia, 'Coefficient of restitution', copy at "
                          "wiki.bitter.house, 2024-01: the HL is a COR valid for the test "
                          "only, not for the material tested)"),
        v_ref=2.0,
        mu=Datum(0.23, ESTIMATE, f"{_NO_MU}; found only tungsten carbide on steel under "
                 "grease (M. D. Marko, Lubricants 7(2):14, 2019, four-ball test) and an "
                 "abstract without values (eutectoid steel on WC-8%Co, dry: scholarcommons."
                 "sc.edu/emec_facpub/133)"),
    ),
    Entry(
        name="lead",
        description="lead (pure)",
        density=Datum(11350.0, CHECKED, "matmake.com, 'Properties of Lead (Pb)', citing F. "
                      "Cardarelli, Materials Handbook (Springer, 2018) and the CRC Handbook of "
                      "Chemistry and Physics, 97th ed. (2016): 11350 kg/m³"),
        E=Datum(1.61e10, CHECKED, "the same page: 16.1 GPa (W. D. Callister, Materials "
                "Science and Engineering (Wiley, 1994): 14 GPa, as quoted at "
                "www.princeton.edu/~maelabs/mae324/glos324/lead.htm)"),
        nu=Datum(0.44, CHECKED, "the same page: 0.44"),
        restitution=Datum(0.2, ESTIMATE, f"{_NO_E}; lead yields at 5-11 MPa "
                          "(Callister 1994: 11 MPa; material-properties.org: 5.5 MPa), so an "
                          "impact at 1 m/s is nearly fully plastic (demonstrations: a lead "
                          "ball hardly bounces on steel, "
                          "demoweb.physics.ucla.edu/content/20-coefficient-restitution)"),
        v_ref=1.0,
        mu=Datum(0.43, SUBSTITUTE, "lead on cast iron, dry, sliding: 0.43 (the handbook table "
                 "reproduced at www.piping-designer.com, 'Friction Coefficient'); no kinetic "
                 "value for lead on steel was found (steel on lead, dry, 0.50 is a static "
                 "one: pickedshares.com, 'Static and sliding friction values')"),
    ),
    Entry(
        name="aluminium",
        description="aluminium alloy 6061-T6",
        density=Datum(2700.0, CHECKED, "6061-T6 datasheet (MatWeb data, www.glemco.com/"
                      "capabilities/material-expertise/aluminum-6061-t6): 2.7 g/cc, 'AA; "
                      "Typical' (Aluminum Association); the same at www.mfgproto.com"),
        E=Datum(6.89e10, CHECKED, "the same datasheet: 68.9 GPa, 'AA; Typical'"),
        nu=Datum(0.33, CHECKED, "the same datasheet: 0.33, 'estimated from trends in similar "
                 "Al alloys'"),
        restitution=Datum(0.8, ESTIMATE, f"{_DUCTILE} (6061-T6 yields at 276 MPa, the same "
                          "datasheet)"),
        v_ref=1.0,
        mu=Datum(0.25, CHECKED, f"{_WYPYCH}: aluminum-steel 0.35 static, 0.25 dynamic (the table "
                 "at www-eng.lbl.gov/~ajdemell/coefficients_of_friction.html gives 0.47, "
                 "sliding, for aluminium on mild steel)"),
    ),
    Entry(
        name="glass",
        description="soda-lime glass (the usual glass bead)",
        density=Datum(2520.0, CHECKED, "Wikipedia, 'Soda-lime glass', table 'Typical "
                      "compositions and properties', container glass: 2.52 g/cm³ (www."
                      "liquisearch.com/soda-lime_glass/typical_compositions_and_properties)"),
        E=Datum(7.2e10, CHECKED, "the same table: 72 GPa (Sci. Rep. 2022, doi:10.1038/"
                "s41598-021-04045-6, Table 1, a soda-lime-magnesia silicate glass: 72.8 ± 0.7 "
                "GPa)"),
        nu=Datum(0.22, CHECKED, "Sci. Rep. 2022, doi:10.1038/s41598-021-04045-6, Table 1: "
                 "0.222 ± 0.003"),
        restitution=Datum(0.9, ESTIMATE, f"{_HARD}; marbles (toy balls, their material "
                          "not stated in what we read) on a floor of unstated material, "
                          "0.92-0.93 (J. Pebralia, Int. J. Appl. Sci. Smart Technol. 4(1):35, "
                          "2022, www.scribd.com/document/583196360): not against steel, not "
                          "used"),
        v_ref=1.0,
        mu=Datum(0.12, CHECKED, f"{_WYPYCH}: glass-steel 0.13 static, 0.12 dynamic (the table "
                 "at schneider-company.com/coefficient-of-friction-reference-chart gives "
                 "0.5-0.7, static, for glass on metal)"),
    ),
    Entry(
        name="alumina",
        description="alumina ceramic, sintered, ≥ 99.5 % Al2O3",
        density=Datum(3984.0, CHECKED, "NIST SRD 150, 'Sintered Alumina', after R. G. Munro, "
                      "J. Am. Ceram. Soc. 80:1919 (1997) (srdata.nist.gov/CeramicDataPortal/"
                      "Pds/Scdaos): 3.984 g/cm³ at 20 °C"),
        E=Datum(4.16e11, CHECKED, "the same table: elastic modulus 416 ± 30 GPa at 20 °C"),
        nu=Datum(0.23, CHECKED, "makeitfrom.com, 'Alumina (Aluminum Oxide, Al2O3)': Poisson's "
                 "ratio 0.22-0.24"),
        restitution=Datum(0.9, ESTIMATE, _HARD),
        v_ref=1.0,
        mu=Datum(0.23, ESTIMATE, f"{_NO_MU}; the nearest found is sapphire (single-crystal "
                 "alumina) on steel, non-lubricated, 0.15 (SIU Center for Advanced Friction "
                 "Studies, frictioncenter.siu.edu/databaseSearch.html), where the copy we "
                 "read does not show whether it is the static or the kinetic column: not "
                 "used"),
    ),
    Entry(
        name="abs",
        description="ABS (acrylonitrile butadiene styrene), moulded or machined",
        density=Datum(1040.0, CHECKED, "CCT Precision, ABS datasheet (www.cctprecision.com/"
                      "materials/abs): specific gravity 1.04"),
        E=Datum(2.39e9, CHECKED, "the same datasheet: tensile modulus 346,000 psi = 2.39e9 Pa"),
        nu=Datum(0.41, CHECKED, "Granta Design MaterialUniverse, 'ABS (extrusion)' (data."
                 "grantadesign.com/materialuniversepolymers): 0.394-0.422, the middle"),
        restitution=Datum(0.8, ESTIMATE, f"{_NO_E}; a glassy polymer loses energy "
                          "viscoelastically (loss coefficient 0.014-0.045, Granta) and yields "
                          "at 30-44 MPa (Granta): 0.8"),
        v_ref=1.0,
        mu=Datum(0.35, CHECKED, "CCT Precision, ABS datasheet: coefficient of friction, dry vs "
                 f"steel, dynamic 0.35; the same in {_WYPYCH}: steel-ABS 0.30 static, 0.35 "
                 "dynamic"),
    ),
)}


def names() -> tuple[str, ...]:
    """The material names, in the table's order."""
    return tuple(TABLE)


def lookup(name: str) -> Entry:
    """The entry called ``name`` (case and surrounding spaces ignored); ``KeyError`` if the
    table has none."""
    key = name.strip().lower() if isinstance(name, str) else name
    if key not in TABLE:
        raise KeyError(name)
    return TABLE[key]
