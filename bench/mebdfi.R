# MEBDFI (R deTestSet) on flex3rpr's compiled index-3 residual, for the work-precision benchmark
# (bench/peers.py runs it): the solver and the form of the paper. The residual
# F(t, y, y') = [q' - v; W' - Q.v; M v' + h + k - Q - G^T lambda; g(q)] and its exact Jacobian are
# the core's, called by MEBDFI directly through deTestSet's compiled-code interface
# (bench/c/f3r_peer.c: f3r_peer_desolve_res, f3r_peer_mebdfi_jac); R only drives.
#
#   Rscript bench/mebdfi.R LIB SCENE index3 RTOL ATOL OUT_CSV [JACOBIAN [OUTPUT_STEP]]
#     LIB          path of libf3r_peer.so
#     JACOBIAN     1: the core's Jacobian (jacres, default), 0: MEBDFI's difference quotients
#
# Writes t, x_p, y_p at every output step (1 ms by default) from 0 to the scene's duration into
# OUT_CSV and one summary line to stdout:
#   F3R_MEBDFI ok=1 cpu_s=... steps=... nre=... nje=... residual_evals=... jacobian_evals=... t_end=...
# cpu_s is the CPU time (user + system, proc.time) of the mebdfi() calls and of the restarts at
# breakpoints only: not R's start, the library load or the output. deTestSet is looked for in
# .libPaths() and in ROOT/build/rlib (the project-local library, ROOT = this script's ../).
#
# The index-3 form: y is ordered by differentiation index, [q | lag | W | v | lambda] (index 1, 2,
# 3), and nind gives the three counts (f3r_peer_r_index_counts), so that MEBDFI divides the error
# weights of v by h and of lambda by h^2 in its Newton and error tests, as its documentation asks
# for index-3 systems. The choices left to a user of MEBDFI:
#   nind    the true indices. Declaring v index 1 (nind = c(nq + 1 + nq, 0, 6)) gains about 3
#           digits at rtol 1e-4 .. 1e-6 on paper_sim3_fixed_free but fails at the first step from
#           rtol 1e-7 on, presumably because the unscaled velocities' Newton corrections carry the
#           rounding of g(q) amplified by 1/h (eps |q| / h), which must stay below atol, while
#           backward Euler's first step needs h below sqrt(2 atol / |v''|): no h satisfies both.
#           nind = c(ny, 0, 0) fails at the first step at every rtol.
#   hini    MEBDFI takes |hini| also as its minimum step (HMIN = |HO| in OVDRIV; it is cut by 10
#           only after a failure, at most 10 times in a run) and deTestSet's default is 1e-5 s,
#           the size of the steps this scene takes at rtol 1e-8 .. 1e-10. 1e-8 s: a first
#           (backward Euler) step that passes the error test at any rtol of the sweep and a
#           minimum step that never binds (the steps here are 1e-6 .. 1e-4 s).
#   maxord  7, the default and largest. maxord 4 or 5 gives wrong trajectories (centimetres off,
#           growing) without any failure at rtol 1e-4 (and 2 digits at 1e-6): the oscillatory
#           flexible modes under the velocities' weak (1/h) error control; 3 is sound but 2x
#           slower from rtol 1e-6 on.
#   atol    one scalar for all components: the h and h^2 scalings already loosen v and lambda
#           (a separate atol for lambda, as the DASPK script's, changes nothing measurable).
# Breakpoints: each segment is integrated by its own mebdfi() call (tcrit = its end) and restarted
# from a consistent state, as in the DASPK script; but MEBDFI does not clamp its steps at TEND
# (deTestSet passes tcrit as TEND): the last step of a segment may pass the breakpoint and be
# interpolated back to it.

# --help (or -h): the header above, before any package is loaded.
if (any(commandArgs(trailingOnly = TRUE)[1] == c("-h", "--help"), na.rm = TRUE)) {
  self <- sub("^--file=", "", grep("^--file=", commandArgs(FALSE), value = TRUE)[1])
  text <- readLines(self)
  cat(sub("^# ?", "", text[seq_len(match(FALSE, startsWith(text, "#")) - 1)]), sep = "\n")
  quit(status = 0)
}
suppressPackageStartupMessages(library(deSolve))

say <- function(...) cat(..., "\n", sep = "")
script_dir <- local({
  a <- grep("^--file=", commandArgs(FALSE), value = TRUE)
  if (length(a)) dirname(normalizePath(sub("^--file=", "", a[1]))) else getwd()
})
root <- dirname(script_dir)
local_lib <- file.path(root, "build", "rlib")
if (dir.exists(local_lib)) .libPaths(c(.libPaths(), local_lib))
if (!suppressPackageStartupMessages(requireNamespace("deTestSet", quietly = TRUE))) {
  say("F3R_MEBDFI ok=0 error=deTestSet is not installed (looked in ",
      paste(.libPaths(), collapse = ", "), "; install it from CRAN: R -e 'install.packages(\"deTestSet\")')")
  quit(status = 1)
}

args <- commandArgs(trailingOnly = TRUE)
if (length(args) < 6) stop("usage: mebdfi.R LIB SCENE index3 RTOL ATOL OUT_CSV [JACOBIAN [OUTPUT_STEP]]")
lib <- normalizePath(args[1])
scene <- normalizePath(args[2])
formulation <- args[3]
rtol <- as.numeric(args[4])
atol <- as.numeric(args[5])
out_csv <- args[6]
use_jac <- if (length(args) >= 7) as.integer(args[7]) != 0 else TRUE
output_step <- if (length(args) >= 8) as.numeric(args[8]) else 1e-3
stopifnot(formulation == "index3", rtol > 0, atol > 0)
hini <- 1e-8  # the first step and MEBDFI's minimum step: see the header
maxord <- 7   # MEBDFI's default and largest (MAXDER): see the header

dyn.load(lib)
dll <- sub("\\.[^.]*$", "", basename(lib))  # the dllname: the file name without extension

message_of <- function() .C("f3r_peer_r_message", m = strrep(" ", 600), PACKAGE = dll)$m
die <- function(what) {
  say("F3R_MEBDFI ok=0 error=", gsub("[\r\n]", " ", what))
  quit(status = 1)
}

o <- .C("f3r_peer_r_open", scene, 2L,
        ny = integer(1), nalg = integer(1), duration = double(1), nbp = integer(1),
        status = integer(1), PACKAGE = dll)
if (o$status != 0) die(message_of())
ny <- o$ny
duration <- o$duration
nind <- .C("f3r_peer_r_index_counts", counts = integer(3), PACKAGE = dll)$counts
if (sum(nind) != ny) die(sprintf("index counts %s do not add up to %d", paste(nind, collapse = ","), ny))
breaks <- if (o$nbp > 0) .C("f3r_peer_r_breakpoints", times = double(o$nbp), n = as.integer(o$nbp),
                            PACKAGE = dll)$times else numeric(0)

init <- .C("f3r_peer_r_initial", y = double(ny), yp = double(ny), status = integer(1), PACKAGE = dll)
if (init$status != 0) die(message_of())

# Output times as the CLI's: k * output_step for k = 1 .. round(duration / output_step), the last
# exactly the duration.
steps_out <- round(duration / output_step)
times <- (0:steps_out) * output_step
times[steps_out + 1] <- duration

invisible(.C("f3r_peer_r_counts", double(3), PACKAGE = dll))  # reset
y <- init$y
yp <- init$yp
bounds <- c(0, breaks[breaks > 0 & breaks < duration], duration)
states <- matrix(NA_real_, nrow = length(times), ncol = ny)
states[1, ] <- y
nst <- 0
nre <- 0
nje <- 0
t_end <- 0
ok <- TRUE
cpu <- 0
warned <- character(0)  # mebdfi's warnings: why it stopped, if it did
for (s in seq_len(length(bounds) - 1)) {
  a <- bounds[s]
  b <- bounds[s + 1]
  inside <- which(times > a & times < b)
  seg <- c(a, times[inside], b)
  t0 <- proc.time()
  printed <- NULL
  out <- tryCatch(
    withCallingHandlers({
      # MEBDFI's Fortran prints its complaints (Rprint) to stdout: keep them for the error message
      printed <- capture.output(
        res <- deTestSet::mebdfi(y = y, dy = yp, times = seg, res = "f3r_peer_desolve_res",
                                 jacres = if (use_jac) "f3r_peer_mebdfi_jac" else NULL,
                                 jactype = if (use_jac) "fullusr" else "fullint",
                                 dllname = dll, initfunc = NULL, parms = NULL, nind = nind,
                                 rtol = rtol, atol = atol, tcrit = b, hini = hini, maxord = maxord,
                                 maxsteps = 1e7, ynames = FALSE))
      res
    },
      warning = function(w) {
        warned <<- c(warned, conditionMessage(w))
        invokeRestart("muffleWarning")
      }),
    error = function(e) { say("mebdfi: ", conditionMessage(e)); NULL })
  t1 <- proc.time()
  cpu <- cpu + sum((t1 - t0)[c("user.self", "sys.self")])
  if (is.null(out)) { ok <- FALSE; break }
  st <- attr(out, "istate")
  nst <- nst + st[2]  # deTestSet's istate, as deSolve's: 2 steps, 3 residual evaluations, 4 Jacobians
  nre <- nre + st[3]
  nje <- nje + st[4]
  reached <- out[nrow(out), 1]
  t_end <- reached
  rows <- match(out[, 1], times)
  keep <- !is.na(rows)
  states[rows[keep], ] <- out[keep, 2:(ny + 1), drop = FALSE]
  if (nrow(out) < length(seg) || reached < b || st[1] < 0) {
    warned <- c(warned, trimws(printed[nzchar(trimws(printed))]))
    ok <- FALSE
    break
  }
  y <- as.numeric(out[nrow(out), 2:(ny + 1)])
  if (s < length(bounds) - 1) {  # a breakpoint: restart from a consistent state, as the CLI
    t0 <- proc.time()
    r <- .C("f3r_peer_r_restart", as.double(b), y = as.double(y), yp = double(ny),
            status = integer(1), PACKAGE = dll)
    cpu <- cpu + sum((proc.time() - t0)[c("user.self", "sys.self")])
    if (r$status != 0) { ok <- FALSE; break }
    y <- r$y
    yp <- r$yp
  }
}
counts <- .C("f3r_peer_r_counts", c = double(3), PACKAGE = dll)$c
if (!ok) die(sprintf("mebdfi stopped at t = %.9g before %.9g: %s", t_end, duration,
                     paste(unique(warned), collapse = "; ")))

pos <- .C("f3r_peer_r_end_effector", as.integer(nrow(states)), as.double(states),
          x = double(nrow(states)), y = double(nrow(states)), PACKAGE = dll)
writeLines(c("t,x_p,y_p", sprintf("%.17g,%.17g,%.17g", times, pos$x, pos$y)), out_csv)
invisible(.C("f3r_peer_r_close", PACKAGE = dll))
say(sprintf("F3R_MEBDFI ok=1 cpu_s=%.9g steps=%d nre=%d nje=%d residual_evals=%.0f jacobian_evals=%.0f t_end=%.17g",
            cpu, as.integer(nst), as.integer(nre), as.integer(nje), counts[1], counts[2], t_end))
