#!/usr/bin/python3
"""Checks the Runge-Kutta tables flex3rpr uses or compares, from first principles.

Tables: the explicit pairs of src/core/solve/erk_tables.c (parsed from the C source, the single source
of truth; with gcc present the parse is compared bit for bit with what the compiler makes of it)
and some SUNDIALS 6.4.1 built-ins, parsed from build/sundials/.../src/arkode/arkode_butcher_*.def.

For each table (method weights b and embedded weights bhat alike):
  * consistency: sum of weights, row sums c_i = sum_j a_ij;
  * algebraic order: the Butcher order conditions b^T Phi(t) = 1/gamma(t) for every rooted tree t
    up to order 10, evaluated in 50-digit arithmetic from the coefficients as written (decimal
    literals taken exactly); the largest residual with the coefficients rounded to doubles is
    reported too (what the C compiler sees);
  * measured order: fixed-step integration in 40-digit arithmetic of a Kepler orbit
    (eccentricity 0.5) plus the non-autonomous w' = w cos t, to t = 5, against the exact solution
    (Kepler's equation), at N = 10, 20, ..., 2560 steps; the order is the least-squares slope of
    log(error) against log(h) over the last three step sizes whose error is below 1e-3 and well
    above the floor that the coefficients' own digits set. Global errors can still be
    pre-asymptotic at 2560 steps (error terms of orders p and p+1 of opposite sign), so also:
  * local-error order: one step of h = 2^-2 ... 2^-14 from 10 points of the exact solution
    (60 digits), errors summed; slope minus one. This is the order the script checks;
  * stability on the imaginary axis, R(z) = 1 + z b^T (I - zA)^{-1} 1, z = iy, in 50 digits:
    y_max = largest y with |R(iy')| <= 1 + 1e-12 on [0, y]; 'strict' = the same with tolerance 0
    (0 when |R(iy)| > 1 for small y); 'weak' = the same with 1e-6. An implicit table with
    |R(iy)| <= 1 + 1e-12 on a linear grid over [0, 20] and a log grid up to 1e6 is reported as
    'whole axis'. Damping: |R(i)|, the factor a resolved oscillation (h*omega = 1) keeps per step.

Output: a Markdown table on stdout (and the per-table details above it); --csv PATH writes the
same table as CSV. Runs with /usr/bin/python3 (numpy not needed; mpmath required).
"""
import argparse
import ast
import csv
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile

import mpmath as mp

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # the checkout (scripts/ci/../..)
ERK_C = os.path.join(ROOT, "src", "core", "solve", "erk_tables.c")
SUNDIALS_DIR = os.path.join(ROOT, "build", "sundials", "sundials-6.4.1+dfsg1", "src", "arkode")
SUNDIALS_TABLES = [  # (file, ARKODE name)
    ("arkode_butcher_erk.def", "ARKODE_FEHLBERG_13_7_8"),
    ("arkode_butcher_erk.def", "ARKODE_VERNER_8_5_6"),
    ("arkode_butcher_dirk.def", "ARKODE_KVAERNO_7_4_5"),
    ("arkode_butcher_dirk.def", "ARKODE_ARK548L2SA_DIRK_8_4_5"),
    ("arkode_butcher_dirk.def", "ARKODE_SDIRK_5_3_4"),
    ("arkode_butcher_dirk.def", "ARKODE_KVAERNO_5_3_4"),
]
DPS = 50  # digits for order conditions and stability
MAX_TREE_ORDER = 10


# ----------------------------------------------------------------------------------------------
# Expressions: C arithmetic on decimal literals, evaluated exactly-as-written (mpmath) and as C
# evaluates it in double precision (Python floats are IEEE doubles, literals correctly rounded).

NUM_RE = re.compile(r"(?<![\w.])((?:\d+\.\d*|\.\d+|\d+)(?:[eE][+-]?\d+)?)")


class Value:
    """A coefficient: exact (mpf of the literals, DPS digits) and as a C double."""

    def __init__(self, exact, double):
        self.exact, self.double = exact, double


def eval_c_expr(text):
    expr = text.strip()
    expr = re.sub(r"\b(?:SUN_RCONST|RCONST)\s*\(", "(", expr)
    expr = re.sub(r"\bSUNRsqrt\b", "sqrt", expr)
    expr = NUM_RE.sub(lambda m: "N('%s')" % m.group(1), expr)
    tree = ast.parse(expr, mode="eval")
    allowed = (ast.Expression, ast.BinOp, ast.UnaryOp, ast.Add, ast.Sub, ast.Mult, ast.Div,
               ast.USub, ast.UAdd, ast.Call, ast.Name, ast.Load, ast.Constant)
    for node in ast.walk(tree):
        if not isinstance(node, allowed):
            raise ValueError("unsupported C expression: %r" % text)
        if isinstance(node, ast.Name) and node.id not in ("N", "sqrt"):
            raise ValueError("unknown name %r in %r" % (node.id, text))
    code = compile(tree, "<coefficient>", "eval")
    with mp.workdps(DPS + 10):
        exact = eval(code, {"__builtins__": {}}, {"N": mp.mpf, "sqrt": mp.sqrt})
        exact = +exact
    double = eval(code, {"__builtins__": {}}, {"N": float, "sqrt": math.sqrt})
    return Value(exact, float(double))


class Table:
    def __init__(self, name, origin, s, q, p, A, b, d, c, explicit, source=""):
        self.name, self.origin, self.s, self.q, self.p = name, origin, s, q, p
        self.A, self.b, self.d, self.c = A, b, d, c  # A[i][j], b[i]... as Value
        self.explicit, self.source = explicit, source
        self.notes = []


def zero():
    return Value(mp.mpf(0), 0.0)


# ----------------------------------------------------------------------------------------------
# src/core/solve/erk_tables.c

def strip_c_comments(text):
    return re.sub(r"/\*.*?\*/|//[^\n]*", " ", text, flags=re.S)


def read_with_includes(path):
    """The C source with its local #include "X.def" data files inlined (erk_tables.def)."""
    folder = os.path.dirname(path)
    return re.sub(r'#include\s+"(\w+\.def)"', lambda m: open(os.path.join(folder, m.group(1))).read(),
                  open(path).read())


def parse_erk_c(path):
    text = strip_c_comments(read_with_includes(path))
    arrays = {}
    for m in re.finditer(r"static\s+const\s+double\s+(\w+)\s*\[([^\]]*)\]\s*=\s*\{(.*?)\};",
                         text, re.S):
        name, size_expr, body = m.group(1), m.group(2), m.group(3)
        size = int(round(eval_c_expr(size_expr).double))
        entries = {}
        for item in split_top_level(body):
            if not item.strip():
                continue
            mm = re.match(r"\s*IJ\(\s*(\d+)\s*,\s*(\d+)\s*,\s*(\d+)\s*\)\s*=(.*)$", item, re.S)
            if mm:
                s_, i, j = int(mm.group(1)), int(mm.group(2)), int(mm.group(3))
                if j >= s_:
                    raise ValueError("%s: column %d >= %d" % (name, j, s_))
                idx, val = i * s_ + j, mm.group(4)
            else:
                mm = re.match(r"\s*\[\s*(\d+)\s*\]\s*=(.*)$", item, re.S)
                if not mm:
                    raise ValueError("%s: cannot parse entry %r" % (name, item))
                idx, val = int(mm.group(1)), mm.group(2)
            if idx in entries:
                raise ValueError("%s: entry %d given twice" % (name, idx))
            if idx >= size:
                raise ValueError("%s: entry %d outside size %d" % (name, idx, size))
            entries[idx] = eval_c_expr(val)
        arrays[name] = [entries.get(k, zero()) for k in range(size)]
    m = re.search(r"f3r_erk_tables\s*\[\s*\]\s*=\s*\{(.*?)\};", text, re.S)
    if not m:
        raise ValueError("no f3r_erk_tables[] in " + path)
    tables = []
    for entry in re.findall(r"\{(.*?)\}", m.group(1), re.S):
        toks = re.findall(r'"(?:[^"\\]|\\.)*"|[A-Za-z_]\w*|\d+|,', entry)
        fields, cur = [], []
        for t in toks:
            if t == ",":
                fields.append(cur)
                cur = []
            else:
                cur.append(t)
        if cur:
            fields.append(cur)
        if len(fields) != 9:
            raise ValueError("table entry with %d fields: %r" % (len(fields), entry))
        name = "".join(t[1:-1] for t in fields[0])
        source = "".join(t[1:-1] for t in fields[1])
        s, q, p = (int(f[0]) for f in fields[2:5])
        Aa, ba, da, ca = (arrays[f[0]] for f in fields[5:9])
        if len(Aa) != s * s or len(ba) != s or len(da) != s or len(ca) != s:
            raise ValueError("%s: array sizes do not match %d stages" % (name, s))
        A = [[Aa[i * s + j] for j in range(s)] for i in range(s)]
        for i in range(s):
            for j in range(i, s):
                if A[i][j].exact != 0:
                    raise ValueError("%s: A[%d][%d] != 0, not explicit" % (name, i, j))
        tables.append(Table(name, "erk_tables.c", s, q, p, A, ba, da, ca, True, source))
    return tables


def split_top_level(body):
    """Splits an initializer list at commas outside parentheses."""
    out, depth, cur = [], 0, []
    for ch in body:
        if ch == "(":
            depth += 1
        elif ch == ")":
            depth -= 1
        if ch == "," and depth == 0:
            out.append("".join(cur))
            cur = []
        else:
            cur.append(ch)
    out.append("".join(cur))
    return out


def gcc_crosscheck(path, tables):
    """Compiles erk_tables.c with a tiny driver and compares every double bit for bit."""
    gcc = shutil.which("gcc") or shutil.which("cc")
    if not gcc:
        return "gcc not found: compiled values not cross-checked"
    driver = r"""
#include <stdio.h>
#include "erk_tables.h"
static void pr(const char* w, const double* v, int n) {
  printf("%s", w);
  for (int k = 0; k < n; ++k) printf(" %a", v[k]);
  printf("\n");
}
int main(void) {
  for (int t = 0; t < f3r_erk_table_count; ++t) {
    const f3r_erk_table* e = &f3r_erk_tables[t];
    if (f3r_erk_table_find(e->name) != e) return 1;
    printf("T %s %d %d %d\n", e->name, e->stages, e->order, e->embedded_order);
    pr("A", e->A, e->stages * e->stages); pr("b", e->b, e->stages);
    pr("d", e->b_embedded, e->stages); pr("c", e->c, e->stages);
  }
  return f3r_erk_table_find("no such table") != NULL;
}
"""
    with tempfile.TemporaryDirectory() as tmp:
        drv = os.path.join(tmp, "driver.c")
        exe = os.path.join(tmp, "driver")
        open(drv, "w").write(driver)
        r = subprocess.run([gcc, "-std=c11", "-Wall", "-Wextra", "-Werror", "-O0",
                            "-I", os.path.dirname(path), drv, path, "-o", exe],
                           capture_output=True, text=True)
        if r.returncode != 0:
            raise SystemExit("gcc failed on erk_tables.c:\n" + r.stderr)
        r = subprocess.run([exe], capture_output=True, text=True)
        if r.returncode != 0:
            raise SystemExit("f3r_erk_table_find misbehaves (driver exit %d)" % r.returncode)
    lines = r.stdout.split("\n")
    byname = {t.name: t for t in tables}
    seen = 0
    for k, line in enumerate(lines):
        if not line.startswith("T "):
            continue
        _, name, s, q, p = line.split()
        t = byname[name]
        if (int(s), int(q), int(p)) != (t.s, t.q, t.p):
            raise SystemExit("%s: compiled sizes/orders differ from the parse" % name)
        mine = {"A": [t.A[i][j] for i in range(t.s) for j in range(t.s)], "b": t.b, "d": t.d,
                "c": t.c}
        for row in lines[k + 1:k + 5]:
            key, *vals = row.split()
            got = [float.fromhex(v) for v in vals]
            want = [v.double for v in mine[key]]
            if got != want:
                bad = [i for i, (g, w) in enumerate(zip(got, want)) if g != w]
                raise SystemExit("%s.%s: compiled doubles differ from the parse at %s"
                                 % (name, key, bad[:5]))
        seen += 1
    if seen != len(tables):
        raise SystemExit("compiled %d tables, parsed %d" % (seen, len(tables)))
    return "gcc: all %d tables compile to exactly the parsed doubles" % seen


# ----------------------------------------------------------------------------------------------
# SUNDIALS .def files

def parse_sundials(path, name):
    text = strip_c_comments(open(path).read())
    i = text.index("ARK_BUTCHER_TABLE(%s," % name)
    j = text.index("return B;", i)
    blk = text[i:j]
    m = re.search(r"ARKodeButcherTable_Alloc\(\s*(\d+)\s*,", blk)
    s = int(m.group(1))
    q = int(re.search(r"B->q\s*=\s*(\d+)\s*;", blk).group(1))
    p = int(re.search(r"B->p\s*=\s*(\d+)\s*;", blk).group(1))
    A = [[zero() for _ in range(s)] for _ in range(s)]
    vec = {"b": [zero() for _ in range(s)], "d": [zero() for _ in range(s)],
           "c": [zero() for _ in range(s)]}
    n_assign = 0
    for mm in re.finditer(r"B->(A|b|d|c)((?:\[\s*\d+\s*\])+)\s*=\s*([^;]*);", blk):
        which, idx, rhs = mm.group(1), [int(x) for x in re.findall(r"\d+", mm.group(2))], \
            mm.group(3)
        v = eval_c_expr(rhs)
        if which == "A":
            A[idx[0]][idx[1]] = v
        else:
            vec[which][idx[0]] = v
        n_assign += 1
    if n_assign != len(re.findall(r"B->(?:A|b|d|c)\s*\[", blk)):
        raise ValueError("%s: some assignments not understood" % name)
    explicit = all(A[i][j].exact == 0 for i in range(s) for j in range(i, s))
    short = name.replace("ARKODE_", "")
    src = "SUNDIALS 6.4.1 %s %s" % (os.path.basename(path), name)
    return Table(short, "sundials-6.4.1", s, q, p, A, vec["b"], vec["d"], vec["c"], explicit, src)


# ----------------------------------------------------------------------------------------------
# Order conditions on rooted trees

def rooted_trees(nmax):
    """Trees as tuples of child ids (nonincreasing); returns (trees, order, gamma) lists."""
    trees, order, gamma = [()], [1], [1]
    by_order = {1: [0]}

    def forests(total, max_id):
        if total == 0:
            yield ()
            return
        for k in range(max_id, -1, -1):
            if order[k] <= total:
                for rest in forests(total - order[k], k):
                    yield (k,) + rest

    for n in range(2, nmax + 1):
        last = len(trees) - 1
        by_order[n] = []
        for f in list(forests(n - 1, last)):
            trees.append(f)
            order.append(n)
            g = n
            for ch in f:
                g *= gamma[ch]
            gamma.append(g)
            by_order[n].append(len(trees) - 1)
    return trees, order, gamma, by_order


TREES = rooted_trees(MAX_TREE_ORDER)
assert [len(TREES[3][n]) for n in range(1, 11)] == [1, 1, 2, 4, 9, 20, 48, 115, 286, 719]


def order_residuals(A, w, s):
    """Max |gamma(t) * w^T Phi(t) - 1| and max |w^T Phi(t) - 1/gamma(t)| per tree order."""
    trees, order, gamma, by_order = TREES
    nz = [[(j, A[i][j]) for j in range(s) if A[i][j] != 0] for i in range(s)]
    g, Ag = [], []
    scaled, absolute = {}, {}
    for k, f in enumerate(trees):
        v = [mp.mpf(1)] * s
        for ch in f:
            v = [v[i] * Ag[ch][i] for i in range(s)]
        g.append(v)
        Ag.append([mp.fsum(a * v[j] for j, a in nz[i]) for i in range(s)])
        phi = mp.fsum(w[i] * v[i] for i in range(s))
        n = order[k]
        scaled[n] = max(scaled.get(n, 0), abs(gamma[k] * phi - 1))
        absolute[n] = max(absolute.get(n, 0), abs(phi - mp.mpf(1) / gamma[k]))
    return scaled, absolute


def algebraic_order(scaled, tol=1e-12):
    p = 0
    for n in range(1, MAX_TREE_ORDER + 1):
        if scaled[n] > tol:
            break
        p = n
    return p


# ----------------------------------------------------------------------------------------------
# Measured order: Kepler orbit (e = 0.5, period 2 pi) plus w' = w cos t, w = exp(sin t)

ECC = mp.mpf("0.5")
T_END = 5
ODE_DPS = 40


def kepler_exact(t):
    t = mp.mpf(t)
    E = mp.findroot(lambda E: E - ECC * mp.sin(E) - t, t)
    den = 1 - ECC * mp.cos(E)
    s = mp.sqrt(1 - ECC ** 2)
    return [mp.cos(E) - ECC, s * mp.sin(E), -mp.sin(E) / den, s * mp.cos(E) / den,
            mp.exp(mp.sin(t))]


def rhs(t, y):
    x, z, u, v, w = y
    r2 = x * x + z * z
    r3 = r2 * mp.sqrt(r2)
    return [u, v, -x / r3, -z / r3, w * mp.cos(t)]


def implicit_stage(t, base, hg, guess, tol):
    """Solves Y = base + hg f(t, Y) by Newton's method (exact Jacobian)."""
    Y = list(guess)
    ct = mp.cos(t)
    for _ in range(60):
        F = rhs(t, Y)
        G = [Y[k] - base[k] - hg * F[k] for k in range(5)]
        x, z = Y[0], Y[1]
        r2 = x * x + z * z
        r3 = r2 * mp.sqrt(r2)
        r5 = r3 * r2
        jxx, jxz, jzz = -1 / r3 + 3 * x * x / r5, 3 * x * z / r5, -1 / r3 + 3 * z * z / r5
        # (I - hg J) d = -G with J = [[0, I, 0], [Jqq, 0, 0], [0, 0, cos t]]
        h2 = hg * hg
        m11, m12, m21, m22 = 1 - h2 * jxx, -h2 * jxz, -h2 * jxz, 1 - h2 * jzz
        r1 = -G[2] - hg * (jxx * G[0] + jxz * G[1])
        r2_ = -G[3] - hg * (jxz * G[0] + jzz * G[1])
        det = m11 * m22 - m12 * m21
        dp0 = (r1 * m22 - m12 * r2_) / det
        dp1 = (m11 * r2_ - m21 * r1) / det
        dq0, dq1 = -G[0] + hg * dp0, -G[1] + hg * dp1
        dw = -G[4] / (1 - hg * ct)
        d = [dq0, dq1, dp0, dp1, dw]
        Y = [Y[k] + d[k] for k in range(5)]
        if max(abs(e) for e in d) < tol:
            return Y
    raise RuntimeError("Newton did not converge")


def rk_step(A, w, c, s, t, y, h):
    nz = [[(j, A[i][j]) for j in range(i) if A[i][j] != 0] for i in range(s)]
    tol = mp.mpf(10) ** (-mp.mp.dps + 4)
    K = []
    for i in range(s):
        base = list(y)
        for j, a in nz[i]:
            ha = h * a
            base = [base[k] + ha * K[j][k] for k in range(5)]
        ti = t + c[i] * h
        if A[i][i] != 0:
            hg = h * A[i][i]
            guess = [base[k] + hg * K[-1][k] for k in range(5)] if K else base
            Y = implicit_stage(ti, base, hg, guess, tol)
        else:
            Y = base
        K.append(rhs(ti, Y))
    return [y[k] + h * mp.fsum(w[i] * K[i][k] for i in range(s) if w[i] != 0) for k in range(5)]


def global_error(A, w, c, s, N):
    h = mp.mpf(T_END) / N
    y = kepler_exact(0)
    for n in range(N):
        y = rk_step(A, w, c, s, n * h, y, h)
    ex = kepler_exact(T_END)
    return max(abs(y[k] - ex[k]) for k in range(5))


def local_error(A, w, c, s, h):
    """Sum over starting points t0 = 0, 0.5, ..., 4.5 of the max-norm error of one step of
    size h from the exact solution (no cancellation between starting points)."""
    total = mp.mpf(0)
    for k in range(10):
        t0 = mp.mpf(k) / 2
        y = rk_step(A, w, c, s, t0, kepler_exact(t0), h)
        ex = kepler_exact(t0 + h)
        total += max(abs(y[i] - ex[i]) for i in range(5))
    return total


N_LIST = [10 * 2 ** k for k in range(9)]  # global: 10 ... 2560 steps to t = 5
H_LIST = [mp.mpf(2) ** -k for k in range(2, 15)]  # local: h = 1/4 ... 1/16384
LOCAL_DPS = 60


def fit_slope(pts, lo, hi):
    """Least-squares slope of log(error) against log(h) over the last three points with
    lo(h) <= error <= hi."""
    use = [(h, e) for h, e in pts if lo(h) <= e <= hi][-3:]
    if len(use) < 2:
        return float("nan")
    xs = [math.log(h) for h, _ in use]
    ys = [math.log(e) for _, e in use]
    xm, ym = sum(xs) / len(xs), sum(ys) / len(ys)
    return sum((x - xm) * (y - ym) for x, y in zip(xs, ys)) / sum((x - xm) ** 2 for x in xs)


def as_mp(A, w, c):
    return [[mp.mpf(a) for a in row] for row in A], [mp.mpf(x) for x in w], [mp.mpf(x) for x in c]


# Coefficients written with D digits satisfy the order conditions only to about 10^-D, which
# puts a floor under the errors (about T_END * residual globally, h * residual per step); fits
# keep to errors 1e4 times above it. resid = max |Phi(t) - 1/gamma(t)| of the literals.

def measured_order(A, w, c, s, resid):
    """Global convergence order: returns (slope, [(N, error)])."""
    pts = []
    with mp.workdps(ODE_DPS):
        A, w, c = as_mp(A, w, c)
        for N in N_LIST:
            try:
                err = global_error(A, w, c, s, N)
            except RuntimeError:  # Newton failed: step far too long for this table
                err = mp.inf
            pts.append((N, float(err)))
            if err < 1e-32:
                break
    lo = max(1e-32, 1e4 * float(resid))
    return fit_slope([(T_END / N, e) for N, e in pts], lambda h: lo, 1e-3), pts


def measured_local_order(A, w, c, s, resid):
    """Local error order minus one: returns (order, [(h, error)])."""
    pts = []
    with mp.workdps(LOCAL_DPS):
        A, w, c = as_mp(A, w, c)
        for h in H_LIST:
            err = local_error(A, w, c, s, h)
            pts.append((float(h), float(err)))
            if err < 1e-50:
                break
    return fit_slope(pts, lambda h: max(1e-50, 1e4 * float(resid) * h), 1e-3) - 1, pts


# ----------------------------------------------------------------------------------------------
# Stability on the imaginary axis

def stability_function(A, b, s):
    """R(z) evaluated by forward substitution (A is lower triangular)."""
    def R(z):
        x = []
        for i in range(s):
            acc = 1 + z * mp.fsum(A[i][j] * x[j] for j in range(i) if A[i][j] != 0)
            x.append(acc / (1 - z * A[i][i]))
        return 1 + z * mp.fsum(b[i] * x[i] for i in range(s))
    return R


def erk_polynomial(A, b, s):
    """Coefficients r_k of R(z) = sum r_k z^k for an explicit table (r_k = b^T A^(k-1) 1)."""
    r = [mp.mpf(1)]
    v = [mp.mpf(1)] * s
    for _ in range(s):
        r.append(mp.fsum(b[i] * v[i] for i in range(s)))
        v = [mp.fsum(A[i][j] * v[j] for j in range(i)) for i in range(s)]
    return r


def abs2_minus_1_poly(r):
    """Coefficients e_k of |R(iy)|^2 - 1 = sum e_k y^k."""
    re_c = [mp.mpf(0)] * len(r)
    im_c = [mp.mpf(0)] * len(r)
    for k, rk in enumerate(r):
        sign = (-1) ** (k // 2)
        if k % 2 == 0:
            re_c[k] = sign * rk
        else:
            im_c[k] = sign * rk
    e = [mp.mpf(0)] * (2 * len(r) - 1)
    for i in range(len(r)):
        for j in range(len(r)):
            e[i + j] += re_c[i] * re_c[j] + im_c[i] * im_c[j]
    e[0] -= 1
    return e


def first_exceedance(absR, tol, y_hi, step):
    """Smallest y in (0, y_hi] where |R(iy)| > 1 + tol, refined by bisection; None if none."""
    lim = 1 + mp.mpf(tol)
    prev = mp.mpf(0)
    n = int(round(y_hi / step))
    for k in range(1, n + 1):
        y = k * mp.mpf(step)
        if absR(y) > lim:
            lo, hi = prev, y
            for _ in range(60):
                mid = (lo + hi) / 2
                if absR(mid) > lim:
                    hi = mid
                else:
                    lo = mid
            return lo
        prev = y
    return None


def stability(t):
    out = {}
    with mp.workdps(DPS):
        A = [[x.exact for x in row] for row in t.A]
        b = [x.exact for x in t.b]
        s = t.s
        R = stability_function(A, b, s)
        out["damping"] = abs(R(mp.mpc(0, 1)))
        if t.explicit:
            r = erk_polynomial(A, b, s)
            e = abs2_minus_1_poly(r)
            lead = next((k for k in range(1, len(e)) if abs(e[k]) > mp.mpf(10) ** -24), None)
            out["lead"] = (lead, e[lead]) if lead is not None else None

            def absR(y):
                return abs(mp.polyval(r[::-1], mp.mpc(0, y)))

            # |R(iy)| ~ |r_s| y^s for large y: nothing stable beyond s + 1
            for key, tol in (("ymax", 1e-12), ("strict", 0.0), ("weak", 1e-6)):
                if key == "strict" and out["lead"] and out["lead"][1] > 0:
                    out[key] = mp.mpf(0)
                    continue
                # an s-stage explicit method is stable on [0, y] only for y <= s - 1
                y = first_exceedance(absR, tol, s, 1e-3)
                if y is None:
                    raise RuntimeError("%s: |R(iy)| <= 1 beyond y = s, impossible" % t.name)
                out[key] = y
            out["whole"] = False
        else:
            def absR(y):
                return abs(R(mp.mpc(0, y)))
            grid = [mp.mpf(k) / 100 for k in range(1, 2001)]
            grid += [mp.mpf(10) ** (k / 50.0) for k in range(-300, 301)]
            bad = [y for y in grid if absR(y) > 1 + mp.mpf(1e-12)]
            if not bad:
                out["whole"] = True
                out["ymax"] = mp.inf
            else:
                out["whole"] = False
                out["ymax"] = first_exceedance(absR, 1e-12, min(bad), min(min(bad) / 1000, 1e-3))
            out["strict"] = None
            out["weak"] = None
            out["Rinf"] = abs(R(mp.mpc(0, 1e30)))
    return out


# ----------------------------------------------------------------------------------------------

def fmt_damping(d):
    """|R(i)| as 1 - x (damped) or 1 + x (amplified)."""
    return "1 %s %.2e" % ("-" if d <= 1 else "+", float(abs(1 - d)))


def fmt(x, digits=4):
    if x is None:
        return "-"
    return mp.nstr(x, digits)


def check(t, do_order):
    res = {}
    with mp.workdps(DPS):
        s = t.s
        Ax = [[x.exact for x in row] for row in t.A]
        Ad = [[mp.mpf(x.double) for x in row] for row in t.A]
        res["sum_b"] = mp.fsum(x.exact for x in t.b)
        res["sum_d"] = mp.fsum(x.exact for x in t.d)
        res["rowsum"] = max(abs(mp.fsum(Ax[i]) - t.c[i].exact) for i in range(s))
        res["rowsum_double"] = max(abs(math.fsum(x.double for x in t.A[i]) - t.c[i].double)
                                   for i in range(s))
        for key, w in (("b", t.b), ("d", t.d)):
            sc, ab = order_residuals(Ax, [x.exact for x in w], s)
            res["alg_" + key] = algebraic_order(sc)
            res["res_" + key] = sc
            p = res["alg_" + key]
            _, abd = order_residuals(Ad, [mp.mpf(x.double) for x in w], s)
            res["dbl_" + key] = max(abd[n] for n in range(1, max(p, 1) + 1))
            res["dbl_at_" + key] = max(range(1, max(p, 1) + 1), key=lambda n: abd[n])
            res["lit_" + key] = max(ab[n] for n in range(1, max(p, 1) + 1))
    if do_order:
        Ax = [[x.exact for x in row] for row in t.A]
        cx = [x.exact for x in t.c]
        for key, w in (("b", t.b), ("d", t.d)):
            w = [x.exact for x in w]
            res["meas_" + key], res["pts_" + key] = measured_order(Ax, w, cx, t.s,
                                                                   res["lit_" + key])
            res["loc_" + key], res["lpts_" + key] = measured_local_order(Ax, w, cx, t.s,
                                                                         res["lit_" + key])
    res["stab"] = stability(t)
    return res


def report_details(t, r):
    kind = "explicit" if t.explicit else "implicit (DIRK)"
    print("## %s  [%s, %d stages, %s]" % (t.name, t.origin, t.s, kind))
    if t.source:
        print("   source: %s" % t.source)
    print("   sum b = %s, sum bhat = %s, max |c_i - sum_j a_ij| = %s (doubles: %.1e)"
          % (mp.nstr(r["sum_b"], 20), mp.nstr(r["sum_d"], 20), mp.nstr(r["rowsum"], 3),
             r["rowsum_double"]))
    print("   max |a_ij| = %.3g, sum |b_i| = %.3g, sum |bhat_i| = %.3g (rounding amplification)"
          % (max(abs(x.double) for row in t.A for x in row), sum(abs(x.double) for x in t.b),
             sum(abs(x.double) for x in t.d)))
    for key, label, claimed in (("b", "method  ", t.q), ("d", "embedded", t.p)):
        sc = r["res_" + key]
        line = " ".join("%d:%.0e" % (n, float(sc[n])) for n in range(1, MAX_TREE_ORDER + 1))
        print("   %s claimed %d, algebraic %d; max |gamma*Phi-1| per tree order: %s"
              % (label, claimed, r["alg_" + key], line))
        print("            max |Phi - 1/gamma| up to that order: literals %.1e, doubles %.1e"
              " (order-%d trees)" % (float(r["lit_" + key]), float(r["dbl_" + key]),
                                     r["dbl_at_" + key]))
        if "pts_" + key in r:
            pts = r["pts_" + key]
            seq = ", ".join("N=%d:%.2e" % (N, e) for N, e in pts)
            print("            measured order %.2f   (errors at t=%d: %s)"
                  % (r["meas_" + key], T_END, seq))
            seq = ", ".join("2^%d:%.1e" % (round(math.log2(h)), e) for h, e in r["lpts_" + key])
            print("            local-error order %.2f (one step, summed over 10 starts: %s)"
                  % (r["loc_" + key], seq))
    st = r["stab"]
    if t.explicit:
        lead = st["lead"]
        if lead:
            print("   |R(iy)|^2 - 1 = %s y^%d + ... near y = 0 (%s)"
                  % (mp.nstr(lead[1], 3), lead[0],
                     "dissipative" if lead[1] < 0 else "ANTI-dissipative: |R| > 1 for small y"))
        print("   imaginary axis: y_max(1e-12) = %s, strict(|R|<=1) = %s, weak(1e-6) = %s, "
              "|R(i)| = %s" % (fmt(st["ymax"], 6), fmt(st["strict"], 6), fmt(st["weak"], 6),
                                fmt_damping(st["damping"])))
    else:
        print("   imaginary axis: %s; |R(i)| = %s; |R(i inf)| = %s"
              % ("whole axis (|R(iy)| <= 1 up to y = 1e6)" if st["whole"]
                 else "|R(iy)| > 1 + 1e-12 from y = %s" % fmt(st["ymax"], 6),
                 fmt_damping(st["damping"]), mp.nstr(st["Rinf"], 3)))
    print()


def row(t, r, do_order):
    st = r["stab"]
    order = "%d(%d)" % (t.q, t.p)
    if r["alg_b"] != t.q or r["alg_d"] != t.p:
        order += " [alg %d(%d)]" % (r["alg_b"], r["alg_d"])
    meas = "%.2f (%.2f)" % (r["meas_b"], r["meas_d"]) if do_order else "-"
    loc = "%.2f (%.2f)" % (r["loc_b"], r["loc_d"]) if do_order else "-"
    if st["whole"]:
        ymax, per = "whole axis", "-"
    else:
        ymax = mp.nstr(st["ymax"], 4)
        per = mp.nstr(st["ymax"] / t.s, 3)
    damp = fmt_damping(st["damping"])
    notes = []
    if t.explicit:
        lead = st["lead"]
        if lead and lead[1] > 0:
            notes.append("|R|>1 for small y (strict y_max = 0); <= 1+1e-6 up to y = %s"
                         % mp.nstr(st["weak"], 4))
        else:
            notes.append("|R|<=1 up to y = %s" % mp.nstr(st["strict"], 4))
    else:
        notes.append("|R(i inf)| = %s" % mp.nstr(st["Rinf"], 3))
    lit = max(r["lit_b"], r["lit_d"])
    if lit > 1e-15:
        notes.append("coefficients hold the order conditions only to %.0e" % float(lit))
    return [t.name, str(t.s), order, meas, loc, ymax, per, damp, "; ".join(notes)]


HEADER = ["name", "stages", "order(embedded)", "measured order", "local-error order",
          "y_max on iR",
          "y_max per stage", "damping |R(i)|", "notes"]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--csv", metavar="PATH", help="also write the summary table as CSV")
    ap.add_argument("--erk-c", default=ERK_C, help="erk_tables.c to check (default: %(default)s)")
    ap.add_argument("--sundials-dir", default=SUNDIALS_DIR,
                    help="SUNDIALS src/arkode with the .def files (default: %(default)s)")
    ap.add_argument("--no-sundials", action="store_true", help="only the tables of erk_tables.c")
    ap.add_argument("--no-gcc", action="store_true", help="skip the compile cross-check")
    ap.add_argument("--quick", action="store_true", help="skip the measured (integrated) orders")
    ap.add_argument("--only", metavar="NAME", action="append",
                    help="check only this table (repeatable)")
    ap.add_argument("--junit", metavar="PATH",
                    help="also write a JUnit XML report, one test case a table (CI's order-condition "
                         "test: --no-sundials --quick --junit PATH, a few seconds)")
    args = ap.parse_args()

    tables = parse_erk_c(args.erk_c)
    print("# Runge-Kutta tables\n")
    print("parsed %d tables from %s" % (len(tables), os.path.relpath(args.erk_c, ROOT)))
    if not args.no_gcc:
        print(gcc_crosscheck(args.erk_c, tables))
    if not args.no_sundials:
        for fname, name in SUNDIALS_TABLES:
            tables.append(parse_sundials(os.path.join(args.sundials_dir, fname), name))
    if args.only:
        tables = [t for t in tables if t.name in args.only]
    print()
    do_order = not args.quick
    rows = []
    failures = []
    failed_tables = {}
    for t in tables:
        r = check(t, do_order)
        report_details(t, r)
        sys.stdout.flush()
        rows.append(row(t, r, do_order))
        before = len(failures)
        if r["alg_b"] < t.q or r["alg_d"] < t.p:
            failures.append("%s: algebraic order %d(%d) below the claimed %d(%d)"
                            % (t.name, r["alg_b"], r["alg_d"], t.q, t.p))
        if do_order and not (abs(r["loc_b"] - t.q) < 0.2 and abs(r["loc_d"] - t.p) < 0.2):
            failures.append("%s: local-error order %.2f(%.2f), claimed %d(%d)"
                            % (t.name, r["loc_b"], r["loc_d"], t.q, t.p))
        if do_order and (r["meas_b"] < t.q - 0.5 or r["meas_d"] < t.p - 0.5):
            print("note: %s: global order %.2f(%.2f) not yet asymptotic at 2560 steps"
                  % (t.name, r["meas_b"], r["meas_d"]), file=sys.stderr)
        if abs(r["sum_b"] - 1) > 1e-14 or abs(r["sum_d"] - 1) > 1e-14 or r["rowsum"] > 1e-14:
            failures.append("%s: weights or row sums inconsistent" % t.name)
        failed_tables[t.name] = failures[before:]
    if args.junit:  # one test case a table: its order conditions at the order it claims
        sys.path.insert(0, os.path.join(ROOT, "nodes"))  # the scripts' shared module
        import flex3rpr_tools

        flex3rpr_tools.write_junit(args.junit, "butcher_tables",
                                   [("butcher_tables", name, "; ".join(failed) or None)
                                    for name, failed in failed_tables.items()])
    def md(cells):
        return "| " + " | ".join(x.replace("|", "\\|") for x in cells) + " |"
    print(md(HEADER))
    print("|" + "|".join("---" for _ in HEADER) + "|")
    for rw in rows:
        print(md(rw))
    if args.csv:
        with open(args.csv, "w", newline="") as f:
            wr = csv.writer(f)
            wr.writerow(HEADER)
            wr.writerows(rows)
    if failures:
        print("\nFAILED:\n  " + "\n  ".join(failures))
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
