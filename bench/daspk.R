# DASPK (R deSolve) on flex3rpr's compiled residual, for the work-precision benchmark
# (bench/peers.py runs it). The residual F(t, y, y') and its Jacobian dF/dy + cj dF/dy'
# are those of the core, called by DASPK directly through deSolve's compiled-code interface
# (bench/c/f3r_peer.c: f3r_peer_desolve_res, f3r_peer_desolve_jac); R only drives.
#
#   Rscript bench/daspk.R LIB SCENE FORMULATION RTOL ATOL OUT_CSV [JACOBIAN [OUTPUT_STEP]]
#     LIB          path of libf3r_peer.so
#     FORMULATION  dae | minimal
#     JACOBIAN     1: the core's Jacobian (jacres, default), 0: DASPK's difference quotients
#
# Writes t, x_p, y_p at every output step (1 ms by default) from 0 to the scene's duration into
# OUT_CSV and one summary line to stdout:
#   F3R_DASPK ok=1 cpu_s=... steps=... nre=... nje=... residual_evals=... jacobian_evals=... t_end=...
# cpu_s is the CPU time (user + system, proc.time) of the daspk() calls and of the restarts at
# breakpoints only: not R's start, the library load or the output.
#
# dae: the 12 multipliers (lambda, mu) are index-2 variables. deSolve's daspk cannot exclude
# algebraic variables from the error test (it never sets DASPK's INFO(16)), but it can scale their
# error weights by 1/h (argument nind, as in radau): the library orders y as
# [q | v | (lag) | W | lambda | mu] so that they come last. Without that scaling DASPK's Newton
# iteration fails at the first step from rtol 1e-8 on (paper_sim3_fixed_free). Their absolute
# tolerance is the CLI's (atol 1e4, at least 1e-6: see src/core/solve/stepper_ida.c); with the scaling a
# plain scalar atol works as well.

# --help (or -h): the header above, before any package is loaded.
if (any(commandArgs(trailingOnly = TRUE)[1] == c("-h", "--help"), na.rm = TRUE)) {
  self <- sub("^--file=", "", grep("^--file=", commandArgs(FALSE), value = TRUE)[1])
  text <- readLines(self)
  cat(sub("^# ?", "", text[seq_len(match(FALSE, startsWith(text, "#")) - 1)]), sep = "\n")
  quit(status = 0)
}
suppressPackageStartupMessages(library(deSolve))

args <- commandArgs(trailingOnly = TRUE)
if (length(args) < 6) stop("usage: daspk.R LIB SCENE dae|minimal RTOL ATOL OUT_CSV [JACOBIAN [OUTPUT_STEP]]")
lib <- normalizePath(args[1])
scene <- normalizePath(args[2])
formulation <- args[3]
rtol <- as.numeric(args[4])
atol <- as.numeric(args[5])
out_csv <- args[6]
use_jac <- if (length(args) >= 7) as.integer(args[7]) != 0 else TRUE
output_step <- if (length(args) >= 8) as.numeric(args[8]) else 1e-3
stopifnot(formulation %in% c("dae", "minimal"), rtol > 0, atol > 0)

dyn.load(lib)
dll <- sub("\\.[^.]*$", "", basename(lib))  # deSolve's dllname: the file name without extension

say <- function(...) cat(..., "\n", sep = "")
message_of <- function() .C("f3r_peer_r_message", m = strrep(" ", 600), PACKAGE = dll)$m
die <- function(what) {
  say("F3R_DASPK ok=0 error=", gsub("[\r\n]", " ", what))
  quit(status = 1)
}

o <- .C("f3r_peer_r_open", scene, as.integer(if (formulation == "dae") 0 else 1),
        ny = integer(1), nalg = integer(1), duration = double(1), nbp = integer(1),
        status = integer(1), PACKAGE = dll)
if (o$status != 0) die(message_of())
ny <- o$ny
nalg <- o$nalg
duration <- o$duration
breaks <- if (o$nbp > 0) .C("f3r_peer_r_breakpoints", times = double(o$nbp), n = as.integer(o$nbp),
                            PACKAGE = dll)$times else numeric(0)

init <- .C("f3r_peer_r_initial", y = double(ny), yp = double(ny), status = integer(1), PACKAGE = dll)
if (init$status != 0) die(message_of())

# Output times as the CLI's: k * output_step for k = 1 .. round(duration / output_step), the last
# exactly the duration.
steps_out <- round(duration / output_step)
times <- (0:steps_out) * output_step
times[steps_out + 1] <- duration

atol_v <- rep(atol, ny)
if (nalg > 0) atol_v[(ny - nalg + 1):ny] <- max(atol * 1e4, 1e-6)
nind <- c(ny - nalg, nalg, 0)

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
warned <- character(0)  # daspk's warnings: why it stopped, if it did
for (s in seq_len(length(bounds) - 1)) {
  a <- bounds[s]
  b <- bounds[s + 1]
  inside <- which(times > a & times < b)
  seg <- c(a, times[inside], b)
  t0 <- proc.time()
  out <- tryCatch(
    withCallingHandlers(
      daspk(y = y, dy = yp, times = seg, res = "f3r_peer_desolve_res",
            jacres = if (use_jac) "f3r_peer_desolve_jac" else NULL,
            jactype = if (use_jac) "fullusr" else "fullint",
            dllname = dll, initfunc = NULL, parms = NULL, nind = nind,
            rtol = rtol, atol = atol_v, tcrit = b, hmax = Inf, maxsteps = 1e6, ynames = FALSE),
      warning = function(w) {
        warned <<- c(warned, conditionMessage(w))
        invokeRestart("muffleWarning")
      }),
    error = function(e) { say("daspk: ", conditionMessage(e)); NULL })
  t1 <- proc.time()
  cpu <- cpu + sum((t1 - t0)[c("user.self", "sys.self")])
  if (is.null(out)) { ok <- FALSE; break }
  st <- attr(out, "istate")
  nst <- nst + st[2]  # deSolve's istate: 2 steps, 3 residual evaluations, 4 Jacobian evaluations
  nre <- nre + st[3]
  nje <- nje + st[4]
  reached <- out[nrow(out), 1]
  t_end <- reached
  rows <- match(out[, 1], times)
  keep <- !is.na(rows)
  states[rows[keep], ] <- out[keep, 2:(ny + 1), drop = FALSE]
  if (nrow(out) < length(seg) || reached < b) { ok <- FALSE; break }
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
if (!ok) die(sprintf("daspk stopped at t = %.9g before %.9g: %s", t_end, duration,
                     paste(unique(warned), collapse = "; ")))

pos <- .C("f3r_peer_r_end_effector", as.integer(nrow(states)), as.double(states),
          x = double(nrow(states)), y = double(nrow(states)), PACKAGE = dll)
writeLines(c("t,x_p,y_p", sprintf("%.17g,%.17g,%.17g", times, pos$x, pos$y)), out_csv)
invisible(.C("f3r_peer_r_close", PACKAGE = dll))
say(sprintf("F3R_DASPK ok=1 cpu_s=%.9g steps=%d nre=%d nje=%d residual_evals=%.0f jacobian_evals=%.0f t_end=%.17g",
            cpu, as.integer(nst), as.integer(nre), as.integer(nje), counts[1], counts[2], t_end))
