# Records strucchange's break-point confidence intervals (Bai 1997) on the
# package's documented examples, so that groupfit's tests need no R.
#   Rscript tests/data/strucchange/record.R      (from the repository root)
# Writes, next to this script: <example>.csv (response y and the regressor
# matrix X as strucchange builds it, intercept column included) and
# intervals.json (strucchange's breaks and confint() ends for m = 1..4, with
# het.reg = het.err = TRUE and with het.reg = het.err = FALSE).
suppressPackageStartupMessages(library(strucchange))
args <- commandArgs(trailingOnly = FALSE)
here <- dirname(normalizePath(sub("^--file=", "", args[grep("^--file=", args)])))

data("Nile"); data("durab"); data("UKDriverDeaths"); data("PhillipsCurve"); data("GermanM1")
seatbelt <- log10(UKDriverDeaths)
seatbelt <- cbind(seatbelt, lag(seatbelt, k = -1), lag(seatbelt, k = -12))
colnames(seatbelt) <- c("y", "ylag1", "ylag12")
seatbelt <- window(seatbelt, start = c(1970, 1), end = c(1984, 12))
uk <- window(PhillipsCurve, start = 1948)
nile <- data.frame(y = as.vector(Nile))

examples <- list(
  nile = list(formula = y ~ 1, data = nile, h = 0.15),
  durab = list(formula = y ~ lag, data = durab, h = 0.15),
  seatbelt = list(formula = y ~ ylag1 + ylag12, data = seatbelt, h = 0.1),
  phillips = list(formula = dw ~ dp1 + du + u1, data = uk, h = 5),
  germanm1 = list(formula = dm ~ dy2 + dR + dR1 + dp + m1 + y1 + R1 + season, data = GermanM1, h = 0.15)
)

num <- function(x) if (is.na(x)) "null" else format(x, scientific = FALSE)
out <- c("{")
first <- TRUE
for (name in names(examples)) {
  ex <- examples[[name]]
  bp <- breakpoints(ex$formula, data = ex$data, h = ex$h, breaks = 4)
  mf <- model.frame(ex$formula, data = ex$data)
  X <- model.matrix(terms(ex$formula, data = ex$data), data = ex$data)
  frame <- data.frame(y = as.vector(model.response(mf)), X, check.names = FALSE)
  write.csv(frame, file.path(here, paste0(name, ".csv")), row.names = FALSE)
  h <- if (ex$h < 1) floor(nrow(X) * ex$h) else ex$h
  rows <- c()
  for (m in 1:4) {
    for (het in c(TRUE, FALSE)) {
      ci <- suppressWarnings(confint(bp, breaks = m, het.reg = het, het.err = het)$confint)
      for (j in seq_len(nrow(ci))) {
        rows <- c(rows, sprintf('    {"m": %d, "het": %s, "break": %d, "lower": %s, "upper": %s}',
                                m, tolower(het), ci[j, 2], num(ci[j, 1]), num(ci[j, 3])))
      }
    }
  }
  entry <- sprintf('  "%s": {"formula": "%s", "h": %d, "n_obs": %d, "intervals": [\n%s\n  ]}',
                   name, paste(deparse(ex$formula), collapse = ""), h, nrow(X), paste(rows, collapse = ",\n"))
  out <- c(out, paste0(if (first) "" else ",\n", entry))
  first <- FALSE
}
out <- c(out, "\n}\n")
writeLines(paste(out, collapse = ""), file.path(here, "intervals.json"))
cat("strucchange", as.character(packageVersion("strucchange")), "\n")
