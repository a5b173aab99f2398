# random_trace.awk -- the pseudo-random input trace of the corpus checks
# (check_corpus.sh, st/two_ways.sh): input lines "NAME DEVICE" (X.. a bit, WX..
# a word); prints a trace of 300 scans of 10 ms, every bit toggling and every
# word over -100..99, from a fixed LCG (exact in doubles), the same on every run.
BEGIN { s = 12345; n = 0 }
NF == 2 { name[n] = $1; word[n] = ($2 ~ /^WX/); n++ }
END {
  if (n == 0) { print "dt"; for (r = 0; r < 300; r++) print 10; exit }
  h = "dt"; for (i = 0; i < n; i++) h = h "," name[i]; print h
  for (r = 0; r < 300; r++) {
    line = 10
    for (i = 0; i < n; i++) {
      s = (s * 69069 + 1) % 4294967296
      v = word[i] ? int(s / 65536) % 200 - 100 : (int(s / 65536) % 4 == 0)
      line = line "," v
    }
    print line
  }
}
