"""Native C FMUs: the generic FMI layers (``c/``), the plant-FMU generator and the native C
twins of the FMU kinds (``twins``: the Shaper and ShapeFilter of ``sampled``, the EKF tuner of
``ekf_tuner``, the STOS controller of ``stos``, the profile generator of ``profiles``, the
reference player of ``reference``, the ScheduledShaper of ``scheduled_shaper`` and the
TrackedShaper of ``tracked_shaper``, each packaged by ``kernel_fmu``).

It may import the design layer (``shapefmu.plants``) and CasADi for code generation; the C it
emits and compiles needs nothing but a C compiler. The generator writes FMI 2.0 Model Exchange +
Co-Simulation FMUs from plant models:

    build_plant_fmu(model, out_path, *, name=None) -> Path
    build_all(models_dir, out_dir) -> list[Path]
    model_from_file(path) -> the model of a *.toml or *.py model file (for the CLI)

``model`` is a model file (``models/*.toml``), a ``shapefmu.plants.Plant``, a python-control
``StateSpace``/``TransferFunction``, or a ``NonlinearPlant`` (a CasADi symbolic ODE, see
``models/pendulum.py``). One FMU is both Model Exchange (derivatives, outputs, directional
derivatives from the Jacobian) and Co-Simulation (exact zero-order-hold step for linear plants,
the matrix exponential computed in C when the step size or a parameter changes; fixed-substep RK4
for nonlinear plants; variable communication steps). It carries its C sources and
``sources/buildDescription.xml``, so fmpy (``fmpy.build.build_platform_binary``) or any tool can
recompile it, and ``binaries/linux64``, ``binaries/win64`` and ``binaries/aarch64-linux`` compiled
here (``compile.py``: gcc, and the mingw-w64 and aarch64 cross compilers where they are installed).

Structure (as the FMI Reference FMUs): ``c/fmi2_layer*.c`` and ``c/fmi3_layer*.c`` are the
hand-written, tested generic layers of FMI 2.0 and 3.0 shared by every native FMU, over
``c/layer_core.c``; ``c/model.h`` is the version-neutral contract with a model part, whose hooks the
layer defaults where a part gives none; ``c/plant_part.c`` is the plants' part (zero-order hold,
RK4, Jacobians, parameter constraints, against ``c/plant_model.h``); the generator writes only the
model of one plant (``model.c``:
sizes, names, start values, parameter constraints; ``plant_casadi.c``: f, g and their Jacobians
from CasADi).

Variable names (``variableNamingConvention="structured"``), stable for SSP parameter bindings:

- inputs, outputs: the names of the model file / plant (``voltage``, ``position``, ``theta_1``);
- parameters: the model file's parameter names in the units written there (``b2``, ``Kt``); a
  vector parameter becomes one scalar per entry, 1-based: ``f[1]``, ``f[2]``, ``lengths[10]``;
  a plant of unknown kind (a python-control LTI) has the matrix entries ``A[i,j]``, ``B[i,j]``,
  ``C[i,j]``, ``D[i,j]``; a nonlinear plant also has ``substep`` (s, the longest RK4 substep);
- states: ``state.<name>`` with the plant's state names (``state.x_r``, ``state.v_f1``; a
  transfer function's realisation has ``state.x_1`` ...), derivatives ``der(state.<name>)``.

Every variable is described: a state by what it is in the plant's kind (``state.x_f1``: deflection of
flexible mode 1), an input, output or parameter as its model file describes it (or by its name); every
unit with its SI base unit; an input's limit |u| <= U as min -U, max U. The DefaultExperiment runs
ten periods of the slowest mode, and the icon draws the plant's resonances.

Parameters are ``tunable`` (settable between Co-Simulation steps and in Model Exchange event mode;
the zero-order-hold matrices are recomputed), except a transfer function's ``num`` and ``den``,
which are ``fixed`` because the states of its realisation depend on them. A value out of a
parameter's range (e.g. ``f[1] <= 0``, ``zeta`` outside [0, 1)) is refused with fmi2Error and a
logged message, as is any non-finite input, a negative step, or a call out of order.
"""

from shapefmu.fmi.native.build import build_all, build_plant_fmu, fmu_file_name, model_from_file
from shapefmu.fmi.native.nonlinear import NonlinearPlant, Output, Variable

__all__ = ["NonlinearPlant", "Output", "Variable", "build_all", "build_plant_fmu", "fmu_file_name", "model_from_file"]
