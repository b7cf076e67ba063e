"""Small C FMUs for the master's tests, compiled here with gcc into temporary .fmu files.

``build_typed_stair(directory)`` builds tests/fmus_c/typed_stair.c (FMI 2.0 Model Exchange +
Co-Simulation, a variable of every FMI 2.0 type, a termination request at ``stop_at``) with the
modelDescription.xml written from the table below; ``build_typed_stair3`` the same model as an FMI 3.0
FMU (typed_stair3.c: Float64, every integer type, Enumeration, Boolean and String). The FMI headers
are fmpy's copy, as another tool compiles with its own.

Variants behave as other exporters' FMUs do (typed_stair_model.h says how, from the standards' text):
``quirks=("PROVISIONAL",)`` keeps a step called with noSetFMUStatePriorToCurrentPoint = false
provisional, ``("RESET_IN_SETUP",)`` resets every value in fmi2SetupExperiment; ``source=True`` declares
only the parameters and the outputs that need no input, as a source such as the Reference FMU Stair;
``dependencies=False`` leaves the ``dependencies`` attribute out of the ModelStructure, as pythonfmu
and the Reference FMUs do; ``missing_library`` links the binary against a library the FMU does not ship.

``build_array_gain3(directory)`` builds tests/fmus_c/array_gain3.c, an FMI 3.0 Co-Simulation FMU with
1-D array variables (Float64 and Int32; the C file lists them).
"""

from __future__ import annotations

import subprocess
import tempfile
import zipfile
from pathlib import Path

import fmpy

from support import FMI_HEADERS

HERE = Path(__file__).resolve().parent.parent / "fmus_c"
GUID = "{6f1c2b7e-typed-stair-0001}"
TOKEN3 = "{6f1c2b7e-typed-stair-0003}"
TOKEN_ARRAYS = "{6f1c2b7e-array-gain-0003}"

# (name, FMI 2.0 type, value reference, causality, variability, start, inputs it depends on); the
# ModelVariables list in this order (the indices of the FMI 2.0 ModelStructure are positions in it).
_VARIABLES = [
    ("x_in", "Real", 0, "input", "continuous", "0", None),
    ("x_out", "Real", 1, "output", "continuous", None, ("x_in",)),
    ("period", "Real", 2, "parameter", "fixed", "1", None),
    ("stop_at", "Real", 3, "parameter", "fixed", "1e+300", None),
    ("level", "Real", 4, "output", "continuous", "0", ()),
    ("der(level)", "Real", 5, "local", "continuous", None, ("x_in",)),
    ("increment", "Integer", 0, "parameter", "fixed", "1", None),
    ("n_in", "Integer", 1, "input", "discrete", "0", None),
    ("counter", "Integer", 2, "output", "discrete", None, ()),
    ("n_out", "Integer", 3, "output", "discrete", None, ("n_in",)),
    ("mode", "Enumeration", 4, "parameter", "fixed", "1", None),
    ("e_in", "Enumeration", 5, "input", "discrete", "1", None),
    ("e_out", "Enumeration", 6, "output", "discrete", None, ("e_in",)),
    ("negate", "Boolean", 0, "parameter", "fixed", "false", None),
    ("b_in", "Boolean", 1, "input", "discrete", "false", None),
    ("b_out", "Boolean", 2, "output", "discrete", None, ("b_in",)),
    ("label", "String", 0, "parameter", "fixed", "stair", None),
    ("s_in", "String", 1, "input", "discrete", "", None),
    ("s_out", "String", 2, "output", "discrete", None, ("s_in",)),
    ("r_in", "Real", 6, "input", "discrete", "0", None),
    ("r_out", "Real", 7, "output", "discrete", None, ("r_in",)),
    ("steps", "Integer", 7, "output", "discrete", None, ()),
    ("provisional_steps", "Integer", 8, "output", "discrete", None, ()),
]
# FMI 3.0: unique value references (typed_stair3.c), and the integer types FMI 2.0 does not have.
_VR3 = {"Real": lambda vr: 1 + vr, "Integer": lambda vr: 10 + vr, "Enumeration": lambda vr: 10 + vr,
        "Boolean": lambda vr: 20 + vr, "String": lambda vr: 30 + vr}
_TYPE3 = {"Real": "Float64", "Integer": "Int32", "Enumeration": "Enumeration", "Boolean": "Boolean", "String": "String"}
WIDE_TYPES = ("Int8", "UInt8", "Int16", "UInt16", "UInt32", "Int64", "UInt64")  # the order of W_INT8 ... W_UINT64
_WIDE_VARIABLES = [row for w, t in enumerate(WIDE_TYPES) for row in (
    (f"{t.lower()}_in", t, 40 + 2 * w, "input", "discrete", "0", None),
    (f"{t.lower()}_out", t, 41 + 2 * w, "output", "discrete", None, (f"{t.lower()}_in",)))]
# A source declares no input: only what does not depend on one (x_out = counter while x_in stays 0).
_SOURCE = ("x_out", "period", "stop_at", "increment", "counter")


def _variables(source: bool, fmi3: bool) -> list[tuple]:
    rows = _VARIABLES + (_WIDE_VARIABLES if fmi3 else [])
    if source:
        rows = [(*row[:6], () if row[6] is not None else None) for row in rows if row[0] in _SOURCE]
    return rows


def _dependencies(row, position, dependencies: bool) -> str:
    if not dependencies:
        return ""  # the standard's default: the output depends on every input
    return f' dependencies="{" ".join(str(position[name]) for name in row[6])}"'


def typed_stair_description(identifier: str, *, source: bool = False, dependencies: bool = True) -> str:
    rows = _variables(source, fmi3=False)
    position = {row[0]: i + 1 for i, row in enumerate(rows)}
    variables = []
    for name, kind, vr, causality, variability, start, _ in rows:
        initial = ' initial="exact"' if causality == "parameter" or name == "level" else ""
        declared = ' declaredType="Direction"' if kind == "Enumeration" else ""
        value = f' start="{start}"' if start is not None else ""
        derivative = ' derivative="5"' if name == "der(level)" else ""
        variables.append(f'    <ScalarVariable name="{name}" valueReference="{vr}" causality="{causality}" '
                         f'variability="{variability}"{initial}><{kind}{declared}{value}{derivative}/></ScalarVariable>')
    outputs = [row for row in rows if row[3] == "output"]
    unknowns = lambda selected: "\n".join(  # noqa: E731
        f'      <Unknown index="{position[row[0]]}"{_dependencies(row, position, dependencies)}/>' for row in selected)
    derivative = [row for row in rows if row[0] == "der(level)"]
    initial = sorted([row for row in outputs if row[0] != "level"] + derivative, key=lambda row: position[row[0]])
    common = f'modelIdentifier="{identifier}" canGetAndSetFMUstate="true" canSerializeFMUstate="true"'
    model_exchange = "" if source else f"<ModelExchange {common}/>"
    return f"""<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription fmiVersion="2.0" modelName="TypedStair" guid="{GUID}" numberOfEventIndicators="0"
    generationTool="shapefmu tests" variableNamingConvention="flat">
  {model_exchange}
  <CoSimulation {common} canHandleVariableCommunicationStepSize="true"/>
  <TypeDefinitions>
    <SimpleType name="Direction">
      <Enumeration>
        <Item name="up" value="1"/>
        <Item name="down" value="2"/>
      </Enumeration>
    </SimpleType>
  </TypeDefinitions>
  <ModelVariables>
{chr(10).join(variables)}
  </ModelVariables>
  <ModelStructure>
    <Outputs>
{unknowns(outputs)}
    </Outputs>
    {f"<Derivatives>{chr(10)}{unknowns(derivative)}{chr(10)}    </Derivatives>" if derivative else ""}
    <InitialUnknowns>
{unknowns(initial)}
    </InitialUnknowns>
  </ModelStructure>
</fmiModelDescription>
"""


def typed_stair3_description(identifier: str, *, source: bool = False, dependencies: bool = True) -> str:
    rows = _variables(source, fmi3=True)
    vr3 = {row[0]: _VR3[row[1]](row[2]) if row[1] in _VR3 else row[2] for row in rows}
    variables = ['    <Float64 name="time" valueReference="0" causality="independent" variability="continuous"/>']
    for name, kind, _, causality, variability, start, _ in rows:
        element = _TYPE3.get(kind, kind)
        attributes = f'name="{name}" valueReference="{vr3[name]}" causality="{causality}"'
        if variability != "continuous":
            attributes += f' variability="{variability}"'
        if kind == "Enumeration":
            attributes += ' declaredType="Direction"'
        if name == "level":
            attributes += ' initial="exact"'
        if name == "der(level)":
            attributes += f' derivative="{vr3["level"]}"'
        if kind == "String":
            body = f"><Start value=\"{start}\"/></String>" if start is not None else "/>"
            variables.append(f"    <String {attributes}{body}")
            continue
        value = f' start="{start}"' if start is not None else ""
        variables.append(f"    <{element} {attributes}{value}/>")

    def unknown(element, row):
        if not dependencies:
            return f'    <{element} valueReference="{vr3[row[0]]}"/>'
        return f'    <{element} valueReference="{vr3[row[0]]}" dependencies="{" ".join(str(vr3[n]) for n in row[6])}"/>'

    outputs = [row for row in rows if row[3] == "output"]
    derivative = [row for row in rows if row[0] == "der(level)"]
    initial = [row for row in outputs if row[0] != "level"] + derivative
    structure = ([unknown("Output", row) for row in outputs] + [unknown("ContinuousStateDerivative", row) for row in derivative]
                 + [unknown("InitialUnknown", row) for row in initial])
    common = f'modelIdentifier="{identifier}" canGetAndSetFMUState="true" canSerializeFMUState="true"'
    model_exchange = "" if source else f"<ModelExchange {common}/>"
    return f"""<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription fmiVersion="3.0" modelName="TypedStair3" instantiationToken="{TOKEN3}"
    generationTool="shapefmu tests" variableNamingConvention="flat">
  {model_exchange}
  <CoSimulation {common} canHandleVariableCommunicationStepSize="true" hasEventMode="false"/>
  <TypeDefinitions>
    <EnumerationType name="Direction">
      <Item name="up" value="1"/>
      <Item name="down" value="2"/>
    </EnumerationType>
  </TypeDefinitions>
  <ModelVariables>
{chr(10).join(variables)}
  </ModelVariables>
  <ModelStructure>
{chr(10).join(structure)}
  </ModelStructure>
</fmiModelDescription>
"""


def compile_fmu(c_file: Path, description: str, identifier: str, out: Path, include: Path, platform: str,
                defines: tuple[str, ...] = (), libraries: tuple[str, ...] = (),
                headers: tuple[str, ...] = ("typed_stair_model.h",)) -> Path:
    """Compile ``c_file`` into binaries/<platform>/<identifier>.so and zip it with ``description``
    and its sources (``c_file`` and the ``headers`` of tests/fmus_c it includes)."""
    out.parent.mkdir(parents=True, exist_ok=True)
    binary = out.with_suffix(".so")
    subprocess.run(["gcc", "-O2", "-shared", "-fPIC", "-std=c99", "-Wall", "-Werror", "-I", str(include), "-I", str(HERE),
                    *(f"-D{name}" for name in defines), "-o", str(binary), str(c_file), *libraries, "-lm"],
                   check=True, capture_output=True, text=True)
    with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as archive:
        archive.writestr("modelDescription.xml", description)
        archive.write(binary, f"binaries/{platform}/{identifier}{fmpy.sharedLibraryExtension}")
        for source in (c_file, *(HERE / header for header in headers)):
            archive.write(source, f"sources/{source.name}")
    binary.unlink()
    return out


def _missing_library(directory: Path, name: str) -> tuple[str, ...]:
    """Linker arguments that make a binary need lib<name>.so, which is built here and never shipped."""
    folder = Path(tempfile.mkdtemp(prefix="missing-", dir=directory))
    stub = folder / "stub.c"
    stub.write_text("int shapefmu_test_needed_symbol(void) { return 0; }\n")
    subprocess.run(["gcc", "-shared", "-fPIC", "-o", str(folder / f"lib{name}.so"), str(stub)], check=True)
    return f"-L{folder}", "-Wl,--no-as-needed", f"-l{name}"


def build_typed_stair(directory: Path, identifier: str = "TypedStair", *, quirks: tuple[str, ...] = (),
                      source: bool = False, dependencies: bool = True, missing_library: str | None = None) -> Path:
    """The TypedStair FMU (see tests/fmus_c/typed_stair.c), or a variant of it (module docstring), in ``directory``."""
    libraries = _missing_library(Path(directory), missing_library) if missing_library else ()
    return compile_fmu(HERE / "typed_stair.c", typed_stair_description(identifier, source=source, dependencies=dependencies),
                       identifier, Path(directory) / f"{identifier}.fmu", FMI_HEADERS, fmpy.platform,
                       tuple(f"QUIRK_{q}" for q in quirks), libraries)


def build_typed_stair3(directory: Path, identifier: str = "TypedStair3", *, quirks: tuple[str, ...] = (),
                       source: bool = False, dependencies: bool = True) -> Path:
    """The TypedStair3 FMU (FMI 3.0, see tests/fmus_c/typed_stair3.c), or a variant of it, in ``directory``."""
    return compile_fmu(HERE / "typed_stair3.c", typed_stair3_description(identifier, source=source, dependencies=dependencies),
                       identifier, Path(directory) / f"{identifier}.fmu", FMI_HEADERS, fmpy.platform_tuple,
                       tuple(f"QUIRK_{q}" for q in quirks), headers=("typed_stair_model.h", "fmi3_common.h"))


ARRAY_GAIN3_DESCRIPTION = f"""<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription fmiVersion="3.0" modelName="ArrayGain3" instantiationToken="{TOKEN_ARRAYS}"
    generationTool="shapefmu tests" variableNamingConvention="structured">
  <CoSimulation modelIdentifier="ArrayGain3" canHandleVariableCommunicationStepSize="true" hasEventMode="false"/>
  <ModelVariables>
    <Float64 name="time" valueReference="0" causality="independent" variability="continuous"/>
    <Float64 name="u" valueReference="1" causality="input" start="1 2 3"><Dimension start="3"/></Float64>
    <Float64 name="k" valueReference="2" causality="parameter" variability="tunable" start="1 1 1"><Dimension start="3"/></Float64>
    <Float64 name="s" valueReference="3" causality="input" start="0"/>
    <Float64 name="y" valueReference="4" causality="output"><Dimension start="3"/></Float64>
    <Float64 name="total" valueReference="5" causality="output"/>
    <Float64 name="x" valueReference="6" causality="output" initial="exact" start="0 0 0"><Dimension start="3"/></Float64>
    <Int32 name="m" valueReference="7" causality="input" variability="discrete" start="0 0"><Dimension start="2"/></Int32>
    <Int32 name="m2" valueReference="8" causality="output" variability="discrete"><Dimension start="2"/></Int32>
  </ModelVariables>
  <ModelStructure>
    <Output valueReference="4" dependencies="1"/>
    <Output valueReference="5" dependencies="1 3"/>
    <Output valueReference="6" dependencies=""/>
    <Output valueReference="8" dependencies="7"/>
    <InitialUnknown valueReference="4" dependencies="1"/>
    <InitialUnknown valueReference="5" dependencies="1 3"/>
    <InitialUnknown valueReference="8" dependencies="7"/>
  </ModelStructure>
</fmiModelDescription>
"""


def build_array_gain3(directory: Path) -> Path:
    """The ArrayGain3 FMU (FMI 3.0 Co-Simulation with array variables, tests/fmus_c/array_gain3.c) in ``directory``."""
    return compile_fmu(HERE / "array_gain3.c", ARRAY_GAIN3_DESCRIPTION, "ArrayGain3", Path(directory) / "ArrayGain3.fmu",
                       FMI_HEADERS, fmpy.platform_tuple, headers=("fmi3_common.h",))
