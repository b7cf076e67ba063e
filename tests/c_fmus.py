"""Small C FMUs for the master's tests, compiled here with gcc into temporary .fmu files.

``build_typed_stair(directory)`` builds tests/fmus_c/typed_stair.c (FMI 2.0 Model Exchange +
Co-Simulation, a variable of every FMI 2.0 type, a termination request at ``stop_at``) with the
modelDescription.xml below; ``build_typed_stair3`` the same model as an FMI 3.0 FMU
(typed_stair3.c: Float64, Int32, Enumeration, Boolean and String). The FMI headers are the ones
the plant FMUs ship.
"""

from __future__ import annotations

import subprocess
import zipfile
from importlib import resources
from pathlib import Path

import fmpy

HERE = Path(__file__).resolve().parent / "fmus_c"
GUID = "{6f1c2b7e-typed-stair-0001}"

_TYPED_STAIR_VARIABLES = """
    <ScalarVariable name="x_in" valueReference="0" causality="input" variability="continuous"><Real start="0"/></ScalarVariable>
    <ScalarVariable name="x_out" valueReference="1" causality="output" variability="continuous"><Real/></ScalarVariable>
    <ScalarVariable name="period" valueReference="2" causality="parameter" variability="fixed" initial="exact"><Real start="1"/></ScalarVariable>
    <ScalarVariable name="stop_at" valueReference="3" causality="parameter" variability="fixed" initial="exact"><Real start="1e+300"/></ScalarVariable>
    <ScalarVariable name="level" valueReference="4" causality="output" variability="continuous" initial="exact"><Real start="0"/></ScalarVariable>
    <ScalarVariable name="der(level)" valueReference="5" causality="local" variability="continuous"><Real derivative="5"/></ScalarVariable>
    <ScalarVariable name="increment" valueReference="0" causality="parameter" variability="fixed" initial="exact"><Integer start="1"/></ScalarVariable>
    <ScalarVariable name="n_in" valueReference="1" causality="input" variability="discrete"><Integer start="0"/></ScalarVariable>
    <ScalarVariable name="counter" valueReference="2" causality="output" variability="discrete"><Integer/></ScalarVariable>
    <ScalarVariable name="n_out" valueReference="3" causality="output" variability="discrete"><Integer/></ScalarVariable>
    <ScalarVariable name="mode" valueReference="4" causality="parameter" variability="fixed" initial="exact"><Enumeration declaredType="Direction" start="1"/></ScalarVariable>
    <ScalarVariable name="e_in" valueReference="5" causality="input" variability="discrete"><Enumeration declaredType="Direction" start="1"/></ScalarVariable>
    <ScalarVariable name="e_out" valueReference="6" causality="output" variability="discrete"><Enumeration declaredType="Direction"/></ScalarVariable>
    <ScalarVariable name="negate" valueReference="0" causality="parameter" variability="fixed" initial="exact"><Boolean start="false"/></ScalarVariable>
    <ScalarVariable name="b_in" valueReference="1" causality="input" variability="discrete"><Boolean start="false"/></ScalarVariable>
    <ScalarVariable name="b_out" valueReference="2" causality="output" variability="discrete"><Boolean/></ScalarVariable>
    <ScalarVariable name="label" valueReference="0" causality="parameter" variability="fixed" initial="exact"><String start="stair"/></ScalarVariable>
    <ScalarVariable name="s_in" valueReference="1" causality="input" variability="discrete"><String start=""/></ScalarVariable>
    <ScalarVariable name="s_out" valueReference="2" causality="output" variability="discrete"><String/></ScalarVariable>
"""
# ModelStructure indices: 1-based positions in the list above.
_TYPED_STAIR_STRUCTURE = """
    <Outputs>
      <Unknown index="2" dependencies="1"/>
      <Unknown index="5" dependencies=""/>
      <Unknown index="9" dependencies=""/>
      <Unknown index="10" dependencies="8"/>
      <Unknown index="13" dependencies="12"/>
      <Unknown index="16" dependencies="15"/>
      <Unknown index="19" dependencies="18"/>
    </Outputs>
    <Derivatives>
      <Unknown index="6" dependencies="1"/>
    </Derivatives>
    <InitialUnknowns>
      <Unknown index="2" dependencies="1"/>
      <Unknown index="6" dependencies="1"/>
      <Unknown index="9" dependencies=""/>
      <Unknown index="10" dependencies="8"/>
      <Unknown index="13" dependencies="12"/>
      <Unknown index="16" dependencies="15"/>
      <Unknown index="19" dependencies="18"/>
    </InitialUnknowns>
"""


def typed_stair_description(identifier: str) -> str:
    common = f'modelIdentifier="{identifier}" canGetAndSetFMUstate="true" canSerializeFMUstate="true"'
    return f"""<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription fmiVersion="2.0" modelName="TypedStair" guid="{GUID}" numberOfEventIndicators="0"
    generationTool="shapefmu tests" variableNamingConvention="flat">
  <ModelExchange {common}/>
  <CoSimulation {common} canHandleVariableCommunicationStepSize="true"/>
  <TypeDefinitions>
    <SimpleType name="Direction">
      <Enumeration>
        <Item name="up" value="1"/>
        <Item name="down" value="2"/>
      </Enumeration>
    </SimpleType>
  </TypeDefinitions>
  <ModelVariables>{_TYPED_STAIR_VARIABLES}  </ModelVariables>
  <ModelStructure>{_TYPED_STAIR_STRUCTURE}  </ModelStructure>
</fmiModelDescription>
"""


def compile_fmu(c_file: Path, description: str, identifier: str, out: Path, include: Path, platform: str) -> Path:
    """Compile ``c_file`` into binaries/<platform>/<identifier>.so and zip it with ``description``."""
    out.parent.mkdir(parents=True, exist_ok=True)
    binary = out.with_suffix(".so")
    subprocess.run(["gcc", "-O2", "-shared", "-fPIC", "-std=c99", "-Wall", "-Werror", "-I", str(include), "-I", str(HERE),
                    "-o", str(binary), str(c_file), "-lm"], check=True, capture_output=True, text=True)
    with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as archive:
        archive.writestr("modelDescription.xml", description)
        archive.write(binary, f"binaries/{platform}/{identifier}{fmpy.sharedLibraryExtension}")
        for source in (c_file, HERE / "typed_stair_model.h"):
            archive.write(source, f"sources/{source.name}")
    binary.unlink()
    return out


def build_typed_stair(directory: Path) -> Path:
    """The TypedStair FMU (see tests/fmus_c/typed_stair.c) in ``directory``."""
    include = Path(str(resources.files("shapefmu.fmi.native") / "c"))
    return compile_fmu(HERE / "typed_stair.c", typed_stair_description("TypedStair"), "TypedStair",
                       Path(directory) / "TypedStair.fmu", include, fmpy.platform)


_TYPED_STAIR3_VARIABLES = """
    <Float64 name="time" valueReference="0" causality="independent" variability="continuous"/>
    <Float64 name="x_in" valueReference="1" causality="input" start="0"/>
    <Float64 name="x_out" valueReference="2" causality="output"/>
    <Float64 name="period" valueReference="3" causality="parameter" variability="fixed" start="1"/>
    <Float64 name="stop_at" valueReference="4" causality="parameter" variability="fixed" start="1e+300"/>
    <Float64 name="level" valueReference="5" causality="output" initial="exact" start="0"/>
    <Float64 name="der(level)" valueReference="6" causality="local" derivative="5"/>
    <Int32 name="increment" valueReference="10" causality="parameter" variability="fixed" start="1"/>
    <Int32 name="n_in" valueReference="11" causality="input" variability="discrete" start="0"/>
    <Int32 name="counter" valueReference="12" causality="output" variability="discrete"/>
    <Int32 name="n_out" valueReference="13" causality="output" variability="discrete"/>
    <Enumeration name="mode" declaredType="Direction" valueReference="14" causality="parameter" variability="fixed" start="1"/>
    <Enumeration name="e_in" declaredType="Direction" valueReference="15" causality="input" variability="discrete" start="1"/>
    <Enumeration name="e_out" declaredType="Direction" valueReference="16" causality="output" variability="discrete"/>
    <Boolean name="negate" valueReference="20" causality="parameter" variability="fixed" start="false"/>
    <Boolean name="b_in" valueReference="21" causality="input" variability="discrete" start="false"/>
    <Boolean name="b_out" valueReference="22" causality="output" variability="discrete"/>
    <String name="label" valueReference="30" causality="parameter" variability="fixed"><Start value="stair"/></String>
    <String name="s_in" valueReference="31" causality="input" variability="discrete"><Start value=""/></String>
    <String name="s_out" valueReference="32" causality="output" variability="discrete"/>
"""
_TYPED_STAIR3_STRUCTURE = "".join(
    f'    <{element} valueReference="{vr}" dependencies="{dependencies}"/>\n'
    for element, vr, dependencies in (
        ("Output", 2, "1"), ("Output", 5, ""), ("Output", 12, ""), ("Output", 13, "11"), ("Output", 16, "15"),
        ("Output", 22, "21"), ("Output", 32, "31"), ("ContinuousStateDerivative", 6, "1"),
        ("InitialUnknown", 2, "1"), ("InitialUnknown", 6, "1"), ("InitialUnknown", 12, ""), ("InitialUnknown", 13, "11"),
        ("InitialUnknown", 16, "15"), ("InitialUnknown", 22, "21"), ("InitialUnknown", 32, "31")))


def typed_stair3_description(identifier: str) -> str:
    common = f'modelIdentifier="{identifier}" canGetAndSetFMUState="true" canSerializeFMUState="true"'
    return f"""<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription fmiVersion="3.0" modelName="TypedStair3" instantiationToken="{{6f1c2b7e-typed-stair-0003}}"
    generationTool="shapefmu tests" variableNamingConvention="flat">
  <ModelExchange {common}/>
  <CoSimulation {common} canHandleVariableCommunicationStepSize="true" hasEventMode="false"/>
  <TypeDefinitions>
    <EnumerationType name="Direction">
      <Item name="up" value="1"/>
      <Item name="down" value="2"/>
    </EnumerationType>
  </TypeDefinitions>
  <ModelVariables>{_TYPED_STAIR3_VARIABLES}  </ModelVariables>
  <ModelStructure>
{_TYPED_STAIR3_STRUCTURE}  </ModelStructure>
</fmiModelDescription>
"""


def build_typed_stair3(directory: Path) -> Path:
    """The TypedStair3 FMU (FMI 3.0, see tests/fmus_c/typed_stair3.c) in ``directory``."""
    include = Path(str(resources.files("shapefmu.fmi.native") / "c"))
    return compile_fmu(HERE / "typed_stair3.c", typed_stair3_description("TypedStair3"), "TypedStair3",
                       Path(directory) / "TypedStair3.fmu", include, fmpy.platform_tuple)
