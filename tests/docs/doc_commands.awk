# doc_commands.awk: the commands a Markdown file shows, for check_doc_commands.sh. Reads the
# code (fenced blocks, blocks indented by 4 spaces, `code spans`) and prints one line per command
# of ours found there: FILE, LINE, PROGRAM, FIRST WORD and OPTIONS, separated by the unit separator
# (\037, so an empty field stays a field); OPTIONS is every --name in the command (bracketed or
# not, =VALUE dropped), space-separated. A command runs from its program's name to the end of the
# span or line, a `;`, `&&`, ` #` comment or the next program's name; a code line ending in `\`,
# or indented deeper than its command's first line (a usage text wrapped over lines), continues
# the command above. A block that shows a session marks its commands with a
# `$ ` prompt, and its other lines are output. POSIX awk (Debian's mawk runs it).

BEGIN {
    progs = "(ribbonctl|ribbon-sim|ribbond|ribbon-grblsim|ribbon-mbsim|ribbon-store-bench|ribbon-fit-family|make)"
    # A program's name: after a space, a slash (build/bin/ribbond) or a parenthesis, followed by
    # a space or the end; so cmake, ribbond.service and daemon/ribbonctl.c are not commands.
    progre = "[ /(]" progs "( |$)"
}

function print_command(file, ln, p, args,    n, w, i, o, opts) {
    n = split(args, w, " ")
    opts = ""
    for (i = 1; i <= n; i++) {
        o = w[i]
        sub(/^[[(|]+/, "", o)
        if (match(o, /^--[a-z0-9][a-z0-9-]*/)) opts = opts " " substr(o, 1, RLENGTH)
    }
    printf "%s\037%d\037%s\037%s\037%s\n", file, ln, p, (n ? w[1] : ""), substr(opts, 2)
}

function emit(s, file, ln,    p, rest, cut, c) {
    s = " " s
    gsub(/\t/, " ", s)
    while (match(s, progre)) {
        p = substr(s, RSTART + 1, RLENGTH - 1)
        sub(/ $/, "", p)
        rest = substr(s, RSTART + RLENGTH)
        if (substr(s, RSTART + RLENGTH - 1, 1) != " ") rest = ""
        # Where this command ends: the next program, a separator or a comment.
        cut = length(rest) + 1
        if (match(" " rest, progre) && RSTART < cut) cut = RSTART
        if ((c = index(rest, ";")) && c < cut) cut = c
        if ((c = index(rest, "&&")) && c < cut) cut = c
        if ((c = index(rest, " #")) && c < cut) cut = c
        print_command(file, ln, p, substr(rest, 1, cut - 1))
        s = " " substr(rest, cut)
    }
}

function flush_code() {
    if (code != "") emit(code, FILENAME, code_ln)
    code = ""
    cont = 0
}

function code_line(text, ln,    ind, s) {
    match(text, /^[ \t]*/)
    ind = RLENGTH
    s = substr(text, RLENGTH + 1)
    # In a block that shows a session ("$ command", then what it printed), only the prompted
    # lines and their `\` continuations are commands; the rest is output.
    if (!cont && substr(s, 1, 2) == "$ ") {
        flush_code()
        prompt = 1
        code = substr(s, 3)
        code_ln = ln
        code_ind = ind
        cont = sub(/\\$/, "", code)
        return
    }
    if (prompt && !cont) {
        flush_code()
        return
    }
    if (cont || (code != "" && ind > code_ind && !match(" " s, progre))) {
        code = code " " s
    } else {
        flush_code()
        code = s
        code_ln = ln
        code_ind = ind
    }
    cont = sub(/\\$/, "", code)
}

# A paragraph (or a table row, or a heading) is joined into one string, so that a code span
# broken over two lines is read whole; n_st / st_off / st_ln map offsets back to line numbers.
function para_add(text, ln) {
    if (para != "") para = para " "
    st_off[++n_st] = length(para) + 1
    st_ln[n_st] = ln
    para = para text
}

function flush_para(    rest, off, a, b, k, ln) {
    rest = para
    off = 0
    while ((a = index(rest, "`")) > 0) {
        b = index(substr(rest, a + 1), "`")
        if (b == 0) break
        ln = st_ln[1]
        for (k = 1; k <= n_st; k++) if (st_off[k] <= off + a) ln = st_ln[k]
        emit(substr(rest, a + 1, b - 1), FILENAME, ln)
        off += a + b
        rest = substr(rest, a + b + 1)
    }
    para = ""
    n_st = 0
}

FNR == 1 {
    flush_code()
    flush_para()
    fence = 0
    prevblank = 1
    incode = 0
    prompt = 0
}

/^[ \t]*```/ {
    flush_para()
    flush_code()
    prompt = 0
    fence = !fence
    next
}

fence {
    code_line($0, FNR)
    next
}

/^[ \t]*$/ {
    flush_para()
    flush_code()
    prevblank = 1
    next
}

/^    / && (prevblank || incode) {
    flush_para()
    code_line($0, FNR)
    incode = 1
    prevblank = 0
    next
}

{
    if (incode) flush_code()
    incode = 0
    prompt = 0
    prevblank = 0
    if ($0 ~ /^[ \t]*(\||#)/) {
        flush_para()
        para_add($0, FNR)
        flush_para()
    } else {
        para_add($0, FNR)
    }
}

END {
    flush_code()
    flush_para()
}
