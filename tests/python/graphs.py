"""Directed graphs of the layout tests (test_module_graph.py, test_scene_imports.py and the
compare tool's test_import_graph.py): one cycle finder for all of them."""


def find_cycle(graph):
    """One cycle of `graph` ({node: the nodes it points to}; a node only pointed to may be
    missing) as a list [a, b, …, a], or None: a depth-first search, nodes and successors in
    sorted order so that the cycle reported is always the same."""
    state = {}  # "open": on the current path, "done": every path from it explored

    def visit(node, path):
        state[node] = "open"
        for nxt in sorted(graph.get(node, ())):
            if state.get(nxt) == "open":
                return path[path.index(nxt):] + [nxt]
            if nxt not in state and (found := visit(nxt, path + [nxt])):
                return found
        state[node] = "done"
        return None

    for start in sorted(graph):
        if start not in state and (found := visit(start, [start])):
            return found
    return None
