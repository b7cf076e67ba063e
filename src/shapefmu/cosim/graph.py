"""Stepping order and algebraic loops, from connections and declared output dependencies.

An output *feeds through* an input when the FMU's ModelStructure lists that input among the
output's ``dependencies`` (FMI 2.0 sec. 2.2.8, FMI 3.0 sec. 2.4.8; an output without a
``dependencies`` attribute depends on every input *the FMU has*: none for a source such as the
Reference FMU Stair or pythonfmu's Csvdemo, whose outputs are results of its step, passed on after it). An algebraic loop is a cycle in the graph whose edges are connections
(output -> input) and feed-throughs (input -> output inside one FMU): around it, the values at a
communication point depend on themselves. Every such cycle's components form one loop group that
the master steps together, iterating on the torn inputs with FMU state rollback.

Outside loops, Gauss-Seidel steps producers before consumers. A cycle of connections that passes
through an input without feed-through (a plant's voltage) is not a loop: the order is cut there, so
the plant steps first with the controller's previous output, and the controller, whose output does
follow its input, steps after it with the plant's new position.
"""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass
class Stage:
    """One item of the stepping order: a single component, or an algebraic-loop group."""

    components: list[str]
    tears: list[tuple[str, str]] = field(default_factory=list)  # (component, input) iterated on
    loop_variables: list[str] = field(default_factory=list)  # the loop's connections, for messages

    @property
    def is_loop(self) -> bool:
        return bool(self.tears)


def output_dependencies(description) -> dict[str, set[str]]:
    """``{output: inputs it depends on}``; every input of the FMU where it declares no dependencies."""
    inputs = {v.name for v in description.modelVariables if v.causality == "input"}
    return {unknown.variable.name: set(inputs) if unknown.dependencies is None
            else {v.name for v in unknown.dependencies if v.name in inputs}
            for unknown in description.outputs}


def _feeds_through(dependencies: dict[str, set[str]], output: str, input_: str | None = None) -> bool:
    """Does ``output`` depend on ``input_`` (or, without one, on any input) at the same instant?
    An output missing from the ModelStructure (which the standard forbids) is taken to depend on every input."""
    declared = dependencies.get(output)
    if declared is None:
        return True
    return bool(declared) if input_ is None else input_ in declared


def _strongly_connected(nodes: list, edges: dict) -> list[list]:
    """Tarjan's algorithm, iterative; components come out in reverse topological order."""
    index, low, on_stack, stack, result = {}, {}, set(), [], []
    counter = 0
    for root in nodes:
        if root in index:
            continue
        work = [(root, iter(edges.get(root, ())))]
        index[root] = low[root] = counter
        counter += 1
        stack.append(root)
        on_stack.add(root)
        while work:
            node, successors = work[-1]
            advanced = False
            for successor in successors:
                if successor not in index:
                    index[successor] = low[successor] = counter
                    counter += 1
                    stack.append(successor)
                    on_stack.add(successor)
                    work.append((successor, iter(edges.get(successor, ()))))
                    advanced = True
                    break
                if successor in on_stack:
                    low[node] = min(low[node], index[successor])
            if advanced:
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                component = []
                while True:
                    item = stack.pop()
                    on_stack.discard(item)
                    component.append(item)
                    if item == node:
                        break
                result.append(component)
    return result


def _topological(nodes: list[str], edges: set[tuple[str, str]]) -> list[str]:
    """Kahn's order of ``nodes`` under ``edges``; where a cycle remains, the earliest node goes next."""
    remaining = list(nodes)
    incoming = {n: {a for a, b in edges if b == n and a in nodes and a != n} for n in nodes}
    order = []
    while remaining:
        ready = [n for n in remaining if not (incoming[n] - set(order))]
        chosen = ready[0] if ready else remaining[0]
        order.append(chosen)
        remaining.remove(chosen)
    return order


def schedule(components: list[str], connections, dependencies: dict[str, dict]) -> list[Stage]:
    """Gauss-Seidel stages for ``components`` (in system order) joined by ``connections``."""
    # Variable graph: output -> input by connection, input -> output by declared feed-through.
    outputs_used = {}
    for c in connections:
        outputs_used.setdefault(c.start_component, set()).add(c.start_connector)
    edges: dict[tuple, list] = {}
    for c in connections:
        edges.setdefault(("out", c.start_component, c.start_connector), []).append(("in", c.end_component, c.end_connector))
        for output in outputs_used.get(c.end_component, ()):
            if _feeds_through(dependencies[c.end_component], output, c.end_connector):
                edges.setdefault(("in", c.end_component, c.end_connector), []).append(("out", c.end_component, output))
    nodes = sorted({n for n in edges} | {m for targets in edges.values() for m in targets})
    loops = [scc for scc in _strongly_connected(nodes, edges) if len(scc) > 1]

    # Components of overlapping loops merge into one group.
    group_of = {name: name for name in components}

    def find(name):
        while group_of[name] != name:
            name = group_of[name]
        return name

    for scc in loops:
        members = sorted({node[1] for node in scc}, key=components.index)
        for other in members[1:]:
            group_of[find(other)] = find(members[0])
    groups: dict[str, list[str]] = {}
    for name in components:
        groups.setdefault(find(name), []).append(name)

    # Order groups by connections; inside a cycle of groups, only edges into feed-through inputs constrain.
    group_edges = {(find(c.start_component), find(c.end_component)) for c in connections} - {(g, g) for g in groups}
    successors: dict[str, list[str]] = {}
    for a, b in group_edges:
        successors.setdefault(a, []).append(b)
    ordered_groups = []
    for scc in reversed(_strongly_connected(list(groups), successors)):
        scc = sorted(scc, key=components.index)
        feedthrough_edges = {
            (find(c.start_component), find(c.end_component)) for c in connections
            if find(c.start_component) in scc and find(c.end_component) in scc
            and any(_feeds_through(dependencies[c.end_component], output, c.end_connector)
                    for output in dependencies[c.end_component])
        }
        ordered_groups.extend(_topological(scc, feedthrough_edges) if len(scc) > 1 else scc)

    stages = []
    for root in ordered_groups:
        members = groups[root]
        if len(members) == 1 and not any(
            c.start_component == c.end_component == members[0] and _feeds_through(dependencies[members[0]], c.start_connector, c.end_connector)
            for c in connections
        ):
            stages.append(Stage(members))
            continue
        position = {name: i for i, name in enumerate(members)}
        inside = [c for c in connections if c.start_component in position and c.end_component in position]
        tears = [(c.end_component, c.end_connector) for c in inside if position[c.start_component] >= position[c.end_component]]
        loop_variables = sorted({f"{node[1]}.{node[2]}" for scc in loops for node in scc if node[1] in position})
        stages.append(Stage(members, tears, loop_variables))
    return stages
