#!/usr/bin/env python3
"""Write the raw bind(C) interfaces of module catchup from the public C headers.

    gen_bindings.py OUTDIR HEADER...

For each HEADER (include/catchup/X.h, and the configured version.h) that
declares CUP_API functions, OUTDIR/bind_X.inc holds one interface block with
an interface body per function, named c_<C name>, with the C parameter names
as dummy names; OUTDIR/bind_callbacks.inc holds the abstract interfaces of
the callback types (typedef int (*cup_x_fn)(...)), named as in C. The
modules of src/fortran `include` these blocks and say themselves which
names are public; the wrappers stay hand-written.

A prototype says most of the mapping (RULES below). What it cannot say is in
ANNOTATE, one line a function: a `double *` that is one scalar out and not
an array, an output written whole (intent(out)), a pointer that may be NULL
(passed as type(c_ptr), value: c_null_ptr or c_loc of an array). SKIP names
the public functions deliberately left without a binding, and why. A
function of a header that these rules cannot map stops the build, naming
it: map it here (a rule, or a line in ANNOTATE or SKIP). Python 3 standard
library only (scripts/setup installs python3)."""
import os
import re
import sys

# Public functions without a bind(C) interface, each with why.
SKIP = {
    'cup_status_merge': 'restated in Fortran as an elemental function (catchup_base.f90)',
    'cup_netlist_switching': 'a table of C function pointers; a scene\'s integrator (cup_scene_integrator) runs switches',
    'cup_integrator_create_switched': 'takes that table; Fortran reaches it through cup_scene_integrator',
    'cup_scene_steady_state': 'catchup-run\'s request (scene key steady_state:); Fortran sets cup_pss_options itself',
    'cup_gate_fn': 'the controller of cup_netlist_set_controller, whose Fortran wrapper states its interface',
}

# What the prototype cannot say, per argument: null (may be NULL:
# type(c_ptr), value), scalar (one value out, not an array), out (written
# whole: intent(out)), out(N) (an array of N written whole), and for a
# function: asc (the Fortran name is the C name, for c_funloc).
ANNOTATE = {
    'cup_polyset_create': 'g=null P=null',
    'cup_polyset_contains': 'g=null',
    'cup_dependency_versions': 'buf=out',
    'cup_integrator_zeta': 'zeta=out',
    'cup_setproj_place': 'u=null x=null',
    'cup_setproj_move': 'u=null x=null',
    'cup_setproj_solve': 'info=out',
    'cup_setproj_project': 'info=out',
    'cup_crowd_desired_velocity': 'u=out(2)',
    'cup_netlist_tran': 'tstep=scalar tstop=scalar',
    'cup_netlist_tran_window': 'tstart=scalar tmax=scalar',
    'cup_netlist_tolerances': 'reltol=scalar abstol=scalar vntol=scalar chgtol=scalar',
    'cup_netlist_steady_state': 'period=scalar',
    'cup_netlist_signals': 'zeta=null out=out',
    'cup_pss_options_default': 'o=out',
    'cup_input_period': 'T=scalar',
    'cup_input_steady_phase': 'T=scalar t0=scalar',
    'cup_scene_steady_phase': 'T=scalar t0=scalar',
    'cup_pss_solve': 'x_guess=null',
    'cup_pss_solve_map': 'x_guess=null',
    'cup_pss_get_info': 'info=out',
    'cup_pss_multipliers': 're=out im=out',
    'cup_pss_trajectory': 't=null x=null zeta=null',
    'cup_measure_period': 'm=out amp=null phase=null',
    'cup_pss_jumps': 't=null',
    'cup_measure_period_jumps': 'jump_t=null m=out amp=null phase=null',
    'cup_scene_load_string': 'dir=null',
    'cup_h5run_sink': 'asc',
    'cup_h5run_event': 'asc',
    'cup_h5run_append': 'sig=null',
    'cup_h5run_describe': 'units=null long_name=null',
    'cup_h5run_get_checkpoint': 'size=scalar rows=scalar events=scalar',
    'cup_h5run_get_double': 'v=scalar',
    'cup_h5_version': 'buf=out',
    'cup_oracle_fn': 'eps_cert=scalar eta_cert=scalar',
}

SCALARS = {'int': 'integer(c_int)', 'double': 'real(c_double)', 'long': 'integer(c_long)',
           'unsigned long': 'integer(c_long)'}  # unsigned long: a size, same width as long


class Unmappable(Exception):
    pass


def read_header(path):
    """(typedef kinds, functions, callback types): each [(name, return type, [(type, name)], line)]"""
    text = open(path).read()
    text = re.sub(r'/\*.*?\*/', lambda m: '\n' * m.group(0).count('\n'), text, flags=re.S)
    text = re.sub(r'//[^\n]*', '', text)
    text = re.sub(r'^[ \t]*#.*$', '', text, flags=re.M)   # CUP_API's own #define
    kinds = {}
    for name in re.findall(r'typedef\s+struct\s+(\w+)\s+\1\s*;', text):
        kinds[name] = 'handle'
    for name in re.findall(r'typedef\s+struct\s+\w+\s*\{[^}]*\}\s*(\w+)\s*;', text):
        kinds[name] = 'struct'
    for name in re.findall(r'typedef\s+enum\s+\w+\s*\{[^}]*\}\s*(\w+)\s*;', text):
        kinds[name] = 'enum'
    callbacks = []
    for m in re.finditer(r'typedef\s+([\w\s\*]+?)\s*\(\s*\*\s*(\w+)\s*\)\s*\(([^;]*)\)\s*;', text):
        kinds[m.group(2)] = 'funptr'
        line = text.count('\n', 0, m.start()) + 1
        callbacks.append((m.group(2), m.group(1).strip(), split_params(re.sub(r'\s+', ' ', m.group(3)), path, line),
                          line))
    funcs = []
    for m in re.finditer(r'\bCUP_API\s+([^;{]*?)\s*;', text, flags=re.S):
        decl = re.sub(r'\s+', ' ', m.group(1))
        line = text.count('\n', 0, m.start()) + 1
        d = re.match(r'(.*?)\b(\w+)\s*\((.*)\)$', decl)
        if not d:
            raise Unmappable('%s:%d: cannot read the declaration "%s"' % (path, line, decl))
        ret, name, params = d.groups()
        funcs.append((name, ret.strip(), split_params(params, path, line), line))
    return kinds, funcs, callbacks


def split_params(params, path, line):
    out, depth, cur = [], 0, ''
    for c in params + ',':
        if c == ',' and depth == 0:
            p = cur.strip()
            cur = ''
            if p and p != 'void':
                m = re.match(r'(.*?)\b(\w+)$', p)
                if not m or not m.group(1).strip():
                    raise Unmappable('%s:%d: parameter "%s" has no name' % (path, line, p))
                out.append((re.sub(r'\s*\*\s*', '*', m.group(1).strip()), m.group(2)))
            continue
        depth += (c == '(') - (c == ')')
        cur += c
    return out


def map_arg(func, ctype, name, note, kinds):
    """(Fortran type, attributes, dimension) of one parameter; an annotation
    that does not apply to it is an error, not a silent no-op."""
    mapped = map_param(func, ctype, name, note, kinds)
    if note and not (note == 'null' and mapped[:2] == ('type(c_ptr)', 'value')
                     or note == 'scalar' and mapped[1] == 'intent(out)' and not mapped[2]
                     or note.startswith('out') and mapped[1] == 'intent(out)'):
        raise Unmappable('%s: ANNOTATE says %s=%s, which does not apply to "%s %s"' % (func, name, note, ctype, name))
    return mapped


def map_param(func, ctype, name, note, kinds):
    const = ctype.startswith('const ')
    base = ctype.replace('const ', '').replace('*', '').strip()
    stars = ctype.count('*')
    kind = kinds.get(base)
    if note == 'null' and stars == 1:
        return 'type(c_ptr)', 'value', ''
    if stars == 0:
        if base in SCALARS:
            return SCALARS[base], 'value', ''
        if kind == 'enum':
            return 'integer(c_int)', 'value', ''
        if kind == 'funptr':
            return 'type(c_funptr)', 'value', ''
    elif stars == 1 and (kind == 'handle' or base == 'void'):
        return 'type(c_ptr)', 'value', ''
    elif stars == 2 and ctype.endswith('const*'):   # T *const *: an array of pointers, c_loc of one
        return 'type(c_ptr)', 'value', ''
    elif stars == 2:
        # T **out: a pointer the call sets (a handle's create, a view); free: reset to NULL
        freeing = kind == 'handle' and re.search(r'_(free|discard|close)$', func)
        return 'type(c_ptr)', 'intent(inout)' if freeing else 'intent(out)', ''
    elif stars == 1:
        ftype = {'char': 'character(kind=c_char)', 'double': 'real(c_double)', 'int': 'integer(c_int)',
                 'long': 'integer(c_long)', 'unsigned long': 'integer(c_long)'}.get(base)
        if kind == 'struct':
            ftype = 'type(%s)' % base
        if ftype:
            intent = 'intent(in)' if const else 'intent(inout)'
            if note == 'scalar' and not const and kind != 'struct':
                return ftype, 'intent(out)', ''
            m = re.fullmatch(r'out(?:\((\d+)\))?', note or '')
            if m and not const:
                intent = 'intent(out)'
            if kind == 'struct':
                return ftype, intent, ''
            return ftype, intent, '(%s)' % (m.group(1) if m and m.group(1) else '*')
    raise Unmappable('%s: parameter "%s %s" has no Fortran mapping' % (func, ctype, name))


def map_result(func, ret, kinds):
    if ret == 'void':
        return None
    if '*' in ret:
        return 'type(c_ptr)'
    if ret in SCALARS:
        return SCALARS[ret]
    if kinds.get(ret) == 'enum':
        return 'integer(c_int)'
    raise Unmappable('%s: returns "%s", which has no Fortran mapping' % (func, ret))


def imports_of(types):
    names = set()
    for t in types:
        m = re.match(r'\w+\((?:kind=)?(\w+)\)', t)
        names.add(m.group(1))
    return sorted(names)


def wrap(line, indent):
    """Free-form lines under 132 columns: break at ', ' with a continuation."""
    out = []
    while len(line) > 100:
        cut = line.rfind(', ', 0, 100)
        if cut < 0:
            break
        out.append(line[:cut + 1] + ' &')
        line = ' ' * (indent + 4) + line[cut + 2:]
    return '\n'.join(out + [line])


def interface_body(name, ret, params, kinds, abstract=False):
    """A function's interface body (c_<name>, bind(C, name=...)), or a
    callback type's abstract one (<name>, bind(C))."""
    notes = dict(a.split('=') if '=' in a else (a, '') for a in ANNOTATE.get(name, '').split())
    fname = name if 'asc' in notes or abstract else 'c_' + name
    dummies = [p[1] for p in params]
    lower = [d.lower() for d in dummies]
    for d, n in notes.items():
        if d != 'asc' and d not in dummies:
            raise Unmappable('%s: ANNOTATE names "%s", which is no parameter of it' % (name, d))
    rtype = map_result(name, ret, kinds)
    res = 'ret'
    if len(set(lower)) != len(lower) or res in lower or fname.lower() in lower:
        raise Unmappable('%s: parameter names clash in Fortran (case-insensitive): %s' % (name, dummies))
    decls = [(t, a, n, dim) for (t, a, dim), n in
             ((map_arg(name, ct, n, notes.get(n), kinds), n) for ct, n in params)]
    what = 'function' if rtype else 'subroutine'
    head = '  %s %s(%s) bind(C%s)%s' % (what, fname, ', '.join(dummies), '' if abstract else ', name="%s"' % name,
                                        ' result(%s)' % res if rtype else '')
    if len(head) > 120:
        head = head.replace(' bind(C', ' &\n      bind(C', 1)
    types = [d[0] for d in decls] + ([rtype] if rtype else [])
    lines = [head, wrap('    import :: ' + ', '.join(imports_of(types)), 4)]
    for t, a, n, dim in decls:
        lines.append('    %s, %s :: %s%s' % (t, a, n, dim))
    if rtype:
        lines.append('    %s :: %s' % (rtype, res))
    lines.append('  end %s %s' % (what, fname))
    return '\n'.join(lines)


def main(argv):
    if len(argv) < 3:
        sys.exit('usage: gen_bindings.py OUTDIR HEADER...')
    outdir, headers = argv[1], argv[2:]
    parsed = [(h,) + read_header(h) for h in headers]
    kinds = {}
    for _, k, _, _ in parsed:
        kinds.update(k)
    seen, errors, texts, abstract = set(), [], {}, []
    for path, _, funcs, callbacks in parsed:
        for name, ret, params, line in callbacks:
            seen.add(name)
            if name in SKIP:
                continue
            try:
                abstract.append(interface_body(name, ret, params, kinds, abstract=True))
            except Unmappable as e:
                errors.append('%s:%d: %s' % (path, line, e))
        stem = os.path.basename(path).split('.')[0]
        bodies = []
        for name, ret, params, line in funcs:
            seen.add(name)
            if name in SKIP:
                continue
            try:
                bodies.append(interface_body(name, ret, params, kinds))
            except Unmappable as e:
                errors.append('%s:%d: %s' % (path, line, e))
        if not bodies:
            continue
        texts['bind_%s.inc' % stem] = ('! Generated from %s by src/fortran/gen_bindings.py: do not edit.\n'
                                       'interface\n%s\nend interface\n'
                                       % (os.path.basename(path), '\n'.join(bodies)))
    texts['bind_callbacks.inc'] = ('! Generated from the callback types of the headers by src/fortran/gen_bindings.py:'
                                   ' do not edit.\nabstract interface\n%s\nend interface\n' % '\n'.join(abstract))
    for name in sorted((set(SKIP) | set(ANNOTATE)) - seen):
        errors.append('gen_bindings.py: SKIP or ANNOTATE names %s, which no header declares' % name)
    for e in errors:
        print('gen_bindings: ' + e + (': map it in src/fortran/gen_bindings.py (a rule, ANNOTATE or SKIP)'
                                      if 'no Fortran mapping' in e else ''), file=sys.stderr)
    if errors:
        return 1
    os.makedirs(outdir, exist_ok=True)
    for name, text in texts.items():   # only what changed: the rest is not recompiled
        out = os.path.join(outdir, name)
        if not os.path.exists(out) or open(out).read() != text:
            with open(out, 'w') as f:
                f.write(text)
    return 0


if __name__ == '__main__':
    sys.exit(main(sys.argv))
