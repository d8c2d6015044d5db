" Vim/Neovim syntax for .tsf specs (tsfc). Keywords kept in sync with the
" grammar by the test `editor_grammars_know_every_keyword`.
if exists("b:current_syntax")
  finish
endif

syn keyword tsfDeclaration tsf controller const fn state input disturbance output signal premise rules rule objective relaxation lyapunov trigger emit precision simulate dynamics monte_carlo sweep columns modes mode adaptive plant
syn keyword tsfKeyword saturate bound energy range sigma is and about at for in with step scale offset converged by estimate robust rate bounds init layer region
syn keyword tsfMembership tri trap gauss sigmoid
syn keyword tsfBuiltin sqrt sin cos tan atan exp log abs sign sinc exprel atan2 min max pi eye zeros ones diag inv det trace transpose norm sum mean dot cross skew blkdiag
syn match tsfNumber "\<\d\+\(\.\d\+\)\=\([eE][+-]\=\d\+\)\="
syn match tsfOperator "=>\|->\|\.\.\|<=\|>=\|\.\*"
syn keyword tsfTodo contained TODO FIXME XXX NOTE
syn match tsfLineComment "//.*$" contains=tsfTodo
syn region tsfBlockComment start="/\*" end="\*/" contains=tsfTodo

hi def link tsfDeclaration Statement
hi def link tsfKeyword Keyword
hi def link tsfMembership Type
hi def link tsfBuiltin Function
hi def link tsfNumber Number
hi def link tsfOperator Operator
hi def link tsfTodo Todo
hi def link tsfLineComment Comment
hi def link tsfBlockComment Comment

let b:current_syntax = "tsf"
